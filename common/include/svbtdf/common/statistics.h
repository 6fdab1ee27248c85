#pragma once
// Small summary statistics shared by the fit, the command line and the tests.

#include <algorithm>
#include <cmath>
#include <vector>

namespace svbtdf::common {

// The median (the upper one for an even count); NaN for no values, so that reports show
// "no data" rather than a number.
inline double Median(std::vector<double> values) {
  if (values.empty()) return std::nan("");
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

}  // namespace svbtdf::common
