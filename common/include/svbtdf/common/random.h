#pragma once
// The house's random numbers. SplitMix64 (Steele, Lea, Flood 2014, "Fast splittable
// pseudorandom number generators"), a bijective 64-bit mixer: hashing seeds, lattice points and
// counters into well-spread bits. And a small, fast generator with independent streams: PCG32 (O'Neill 2014,
// "PCG: A family of simple fast space-efficient statistically good algorithms for random number
// generation"). The Monte Carlo tracer gives every fixed chunk of paths its own stream, seeded
// from (seed, chunk index), so its results do not depend on how chunks are spread over threads.

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

}  // namespace svbtdf::common
