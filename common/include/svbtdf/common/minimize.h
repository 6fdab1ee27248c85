#pragma once
// One-dimensional minimisation shared by the fit (alpha, paper eq. 18) and the model validation.

#include <functional>

namespace svbtdf::common {

// Golden-section search for a minimum of a unimodal f on [lo, hi], to an interval narrower than
// `tolerance`; returns the midpoint of the final interval. Reuses one evaluation per step.
double GoldenSectionSearch(const std::function<double(double)>& f, double lo, double hi, double tolerance);

}  // namespace svbtdf::common
