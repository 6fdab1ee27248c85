#include "svbtdf/common/random.h"

namespace svbtdf::common {

const NormalZiggurat& TheNormalZiggurat() {
  static const NormalZiggurat ziggurat = [] {
    // The layers' common area for r = 3.6541528853610088 (Marsaglia and Tsang's 256-layer
    // constants): r f(r) plus the tail's integral. With it the recursion below closes, f(x[255])
    // + area / x[255] = 1 to 2e-11, so the top layer ends at x[256] = 0.
    constexpr double kArea = 0.00492867323399;
    const auto f = [](double x) { return std::exp(-0.5 * x * x); };
    const double r = NormalZiggurat::kTailStart;
    NormalZiggurat z;
    z.x[0] = kArea / f(r);
    z.x[1] = r;
    for (int i = 1; i < NormalZiggurat::kLayers - 1; ++i) z.x[i + 1] = std::sqrt(-2.0 * std::log(f(z.x[i]) + kArea / z.x[i]));
    z.x[NormalZiggurat::kLayers] = 0.0;
    for (int i = 0; i <= NormalZiggurat::kLayers; ++i) z.f[i] = f(z.x[i]);  // f[0] is never read
    return z;
  }();
  return ziggurat;
}

}  // namespace svbtdf::common
