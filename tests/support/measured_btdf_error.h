#pragma once
// Test support: how well a processed store measured the analytic truth. For every valid texel and
// dot, the store's R (mean of its channels) against the truth's R at the true light and view
// directions; samples below 5% of the texel's peak are left out (their relative error is noise).

#include <algorithm>
#include <cmath>
#include <vector>

#include "svbtdf/fit/slice_store.h"
#include "svbtdf/model/dual_microfacet.h"
#include "svbtdf/simulate/truth_io.h"

namespace svbtdf::testing {

// Median |R / R_true - 1| over the samples of `store`; the dots' true positions are `dots` and the
// camera's true centre `camera`. Returns NaN when no sample qualifies; `count` receives their number.
inline double MedianBtdfError(const fit::SliceStore& store, const simulate::MaterialTruth& material, const std::vector<model::Vec3>& dots,
                              const model::Vec3& camera, size_t* count = nullptr) {
  std::vector<double> errors;
  std::vector<float> samples;
  const fit::TexelGeometry& g = store.geometry();
  for (int64_t t = 0; t < g.num_texels(); ++t) {
    const int x = static_cast<int>(t % g.texels_x), y = static_cast<int>(t / g.texels_x);
    if (store.mask().at(x, y) == 0) continue;
    store.ReadSamples(t, &samples);
    const auto ndf = material.TexelNdf(x, y);
    const model::DualMicrofacetParams params = material.Params(x, y);
    const model::Vec3 centre = g.TexelCentre(t);
    const model::Vec3 view = (camera - centre).normalized();
    std::vector<double> r_true;
    for (const model::Vec3& p : dots) r_true.push_back(model::Luminance(model::EvaluateMaterial(*ndf, params, (p - centre).normalized(), view)));
    const double peak = *std::max_element(r_true.begin(), r_true.end());
    for (size_t q = 0; q < r_true.size(); ++q) {
      const double measured = (samples[3 * q] + samples[3 * q + 1] + samples[3 * q + 2]) / 3.0;
      if (r_true[q] >= 0.05 * peak && std::isfinite(measured)) errors.push_back(std::abs(measured / r_true[q] - 1));
    }
  }
  if (count) *count = errors.size();
  if (errors.empty()) return std::nan("");
  std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
  return errors[errors.size() / 2];
}

}  // namespace svbtdf::testing
