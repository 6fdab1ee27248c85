#pragma once
// Small summary statistics shared by the fit, the command line and the tests.

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

namespace svbtdf::common {

// The q-quantile (0 <= q <= 1) as the value of rank floor(q n) of n values (the largest for q = 1);
// NaN for no values, so that reports show "no data" rather than a number.
inline double Quantile(std::vector<double> values, double q) {
  if (values.empty()) return std::nan("");
  const size_t rank = std::min(values.size() - 1, static_cast<size_t>(std::clamp(q, 0.0, 1.0) * values.size()));
  std::nth_element(values.begin(), values.begin() + rank, values.end());
  return values[rank];
}

// The median (the upper one for an even count); NaN for no values.
inline double Median(std::vector<double> values) { return Quantile(std::move(values), 0.5); }

}  // namespace svbtdf::common
