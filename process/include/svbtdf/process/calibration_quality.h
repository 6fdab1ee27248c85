#pragma once
// The quality checks of a calibration (docs/quality.md, "calibrate"): dots far off the fitted
// grid, dots with no blob, a high reprojection error, many board views dropped. The warning
// vocabulary and the thresholds are fit/quality.h's, which checks the other stages.

#include <string>
#include <vector>

#include "svbtdf/calib/session_calibration.h"
#include "svbtdf/fit/quality.h"

namespace svbtdf::process {

// `file` is how the warnings name the calibration (e.g. SESSION/calibration.json).
std::vector<fit::QualityWarning> CheckCalibration(const calib::SessionCalibration& calibration, const std::string& file);

}  // namespace svbtdf::process
