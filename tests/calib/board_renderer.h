#pragma once
// Test support: renders a chessboard seen by a known pinhole camera with Brown-Conrady
// distortion, so calibration can be checked against the truth without real photos.
#include <opencv2/core.hpp>

#include "svbtdf/calib/camera_calibration.h"

namespace svbtdf::calib::testing {

// Renders `board` (a chessboard: cols x rows inner corners) at pose (rvec, tvec in mm) into an
// 8-bit image, anti-aliased by 2x2 supersampling, with mild Gaussian noise when noise_sigma > 0.
cv::Mat RenderChessboard(const BoardSpec& board, const CameraModel& camera, const cv::Vec3d& rvec,
                         const cv::Vec3d& tvec, double noise_sigma, uint64_t seed);

}  // namespace svbtdf::calib::testing
