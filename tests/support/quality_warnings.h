#pragma once
// Looking up quality warnings by their check name, for the tests of fit/quality.h and
// process/calibration_quality.h.

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

#include "svbtdf/fit/quality.h"

namespace svbtdf::testing {

inline std::vector<std::string> Checks(const std::vector<fit::QualityWarning>& warnings) {
  std::vector<std::string> checks;
  for (const fit::QualityWarning& w : warnings) checks.push_back(w.check);
  return checks;
}

inline bool Has(const std::vector<fit::QualityWarning>& warnings, const std::string& check) {
  const auto checks = Checks(warnings);
  return std::find(checks.begin(), checks.end(), check) != checks.end();
}

inline const fit::QualityWarning& Find(const std::vector<fit::QualityWarning>& warnings, const std::string& check) {
  for (const fit::QualityWarning& w : warnings) {
    if (w.check == check) return w;
  }
  throw std::runtime_error("no " + check);
}

}  // namespace svbtdf::testing
