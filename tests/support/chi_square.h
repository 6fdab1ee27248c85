#pragma once
// Test support: Pearson's chi-square of observed against expected counts, and the bound a
// correct sampler stays below.
#include <cmath>
#include <vector>

namespace svbtdf::testing {

struct ChiSquareStatistic {
  double chi2 = 0;
  int bins = 0;
};

// Pearson's chi-square of observed against expected counts. Bins expected to hold fewer than 20
// are pooled into one bin, which starts with `pooled_observed` and `pooled_expected` (a mass
// that has no cell, such as the draws a sampler failed).
inline ChiSquareStatistic PooledChiSquare(const std::vector<double>& observed, const std::vector<double>& expected,
                                          double pooled_observed = 0, double pooled_expected = 0) {
  ChiSquareStatistic result;
  for (size_t c = 0; c < observed.size(); ++c) {
    const double e = expected[c];
    if (e < 20) {
      pooled_observed += observed[c];
      pooled_expected += e;
      continue;
    }
    result.chi2 += (observed[c] - e) * (observed[c] - e) / e;
    ++result.bins;
  }
  if (pooled_expected > 20) {
    result.chi2 += (pooled_observed - pooled_expected) * (pooled_observed - pooled_expected) / pooled_expected;
    ++result.bins;
  }
  return result;
}

// A bound that a chi-square with `bins` - 1 degrees of freedom exceeds with p < 1e-4 (about the
// mean + 4.5 standard deviations).
inline double ChiSquareBound(int bins) { return (bins - 1) + 4.5 * std::sqrt(2.0 * (bins - 1)); }

}  // namespace svbtdf::testing
