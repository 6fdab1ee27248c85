#pragma once
// Calibrating a capture session (docs/calibration-format.md): the camera from the Zhang board
// views, the sample plane from the board in the sample holder, the monitor and its dots from the
// all-dots image, and the radiometry from the session's description and dark frames.

#include "svbtdf/calib/camera_calibration.h"
#include "svbtdf/calib/session_calibration.h"
#include "svbtdf/session/session.h"

namespace svbtdf::calib {

struct CalibrateSessionOptions {
  CalibrationOptions camera;
  bool progress = true;
};

// Reads only the calibration captures (board/*, sample_plane/*, all_dots/*, dark/*). Throws
// svbtdf::Error naming the image or file for anything it cannot use (a board not found in the
// sample-plane view, a dot grid mostly not found, mismatched sizes, unreadable images).
SessionCalibration CalibrateSession(const session::Session& session, const CalibrateSessionOptions& options = {});

// The dots found in an all-dots image, matched to the displayed grid (exposed for tests).
struct DotDetection {
  std::vector<Eigen::Vector2d> centroids;  // every blob found (pixels)
  std::vector<int> blob_of_dot;            // per planned dot: index into centroids, -1 if missing
};

}  // namespace svbtdf::calib
