#pragma once
// The house's random numbers. SplitMix64 (Steele, Lea, Flood 2014, "Fast splittable
// pseudorandom number generators"), a bijective 64-bit mixer: hashing seeds, lattice points and
// counters into well-spread bits. And a small, fast generator with independent streams: PCG32 (O'Neill 2014,
// "PCG: A family of simple fast space-efficient statistically good algorithms for random number
// generation"). The Monte Carlo tracer gives every fixed chunk of paths its own stream, seeded
// from (seed, chunk index), so its results do not depend on how chunks are spread over threads.
// And standard normal variates by the ziggurat method, from any source of 64 random bits.

#include <array>
#include <cmath>
#include <cstdint>

namespace svbtdf::common {

// One SplitMix64 step: nearby inputs (1, 2, 3, ...) give unrelated outputs.
constexpr uint64_t SplitMix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

class Pcg32 {
 public:
  // `stream` selects one of 2^63 independent sequences; `seed` the starting point within it.
  Pcg32(uint64_t seed, uint64_t stream) : increment_((stream << 1u) | 1u) {
    NextUint32();
    state_ += SplitMix64(seed);
    NextUint32();
  }

  uint32_t NextUint32() {
    const uint64_t old = state_;
    state_ = old * 6364136223846793005ULL + increment_;
    const auto xorshifted = static_cast<uint32_t>(((old >> 18u) ^ old) >> 27u);
    const auto rotation = static_cast<uint32_t>(old >> 59u);
    return (xorshifted >> rotation) | (xorshifted << ((~rotation + 1u) & 31u));
  }

  // Uniform on [0, 1) with 53 random bits.
  double NextDouble() {
    const uint64_t high = NextUint32() >> 5;  // 27 bits
    const uint64_t low = NextUint32() >> 6;   // 26 bits
    return static_cast<double>((high << 26) | low) * 0x1.0p-53;
  }

 private:
  uint64_t state_ = 0;
  uint64_t increment_;
};

// Uniform on [0, 1) from the top 53 of 64 random bits.
constexpr double UnitInterval(uint64_t bits) { return static_cast<double>(bits >> 11) * 0x1.0p-53; }

// The ziggurat of Marsaglia and Tsang (2000, "The ziggurat method for generating random
// variables") under exp(-x^2 / 2): 256 layers of equal area, layer i the rectangle
// [0, x[i]] x [f(x[i]), f(x[i+1])], layer 0 the base [0, r] x [0, f(r)] and the tail beyond r,
// given the width x[0] = (its area) / f(r). Built once from r and the area (random.cc).
struct NormalZiggurat {
  static constexpr int kLayers = 256;
  static constexpr double kTailStart = 3.6541528853610088;  // r
  std::array<double, kLayers + 1> x;  // x[1] = r > x[2] > ... > x[256] = 0
  std::array<double, kLayers + 1> f;  // exp(-x^2 / 2)
};
const NormalZiggurat& TheNormalZiggurat();

// A standard normal variate. `next_bits()` returns 64 uniformly random bits per call. About 99%
// of variates take one call, a multiply and two table reads; the rest test the curve (one exp) or
// sample the tail. The layer comes from the low 8 bits, the sign from bit 8 and the position in
// the layer from the top 53 bits, so that they are independent (Doornik 2005 showed the
// correlation when one 32-bit draw serves both).
template <typename NextBits>
double StandardNormal(NextBits&& next_bits) {
  const NormalZiggurat& z = TheNormalZiggurat();
  for (;;) {
    const uint64_t bits = next_bits();
    const int layer = static_cast<int>(bits & 0xff);
    const double sign = (bits & 0x100) ? -1.0 : 1.0;
    const double x = UnitInterval(bits) * z.x[layer];
    if (x < z.x[layer + 1]) return sign * x;  // inside the curve whatever the height
    if (layer == 0) {
      // The tail beyond r (Marsaglia 1964): r + a, a exponential with rate r, accepted with
      // probability exp(-a^2 / 2).
      for (;;) {
        const double a = -std::log(1.0 - UnitInterval(next_bits())) / NormalZiggurat::kTailStart;
        const double b = -std::log(1.0 - UnitInterval(next_bits()));
        if (2.0 * b >= a * a) return sign * (NormalZiggurat::kTailStart + a);
      }
    }
    // The wedge between the layer's inner rectangle and the curve.
    const double y = z.f[layer] + (z.f[layer + 1] - z.f[layer]) * UnitInterval(next_bits());
    if (y < std::exp(-0.5 * x * x)) return sign * x;
  }
}

}  // namespace svbtdf::common
