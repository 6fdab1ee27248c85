#pragma once
// Calibrating any camera from a folder of board photos (`svbtdf calibrate --images`), and the
// file that result is written to (docs/calibration-format.md, "Camera calibration file").

#include <filesystem>
#include <string>
#include <vector>

#include "svbtdf/calib/camera_calibration.h"

namespace svbtdf::calib {

inline constexpr const char* kCameraCalibrationFormat = "svbtdf-camera-calibration";
inline constexpr int kCameraCalibrationVersion = 1;

// Reads every photo (8- or 16-bit, grey or colour; a 16-bit file is stretched to its own maximum,
// as camera-native files often hold 12-bit values), detects `board` in it and calibrates. Throws
// svbtdf::Error naming the file for a photo that cannot be read or whose size differs from the
// first one's, and CalibrateCamera's errors.
CalibrationReport CalibrateFromPhotos(const std::vector<std::string>& files, const BoardSpec& board,
                                      const CalibrationOptions& options, bool progress = true);

// Writes the camera calibration file atomically: format, version, board and the "camera" block
// of calibration.json (ToJson).
void WriteCameraCalibration(const std::filesystem::path& path, const BoardSpec& board, const CalibrationReport& report);

}  // namespace svbtdf::calib
