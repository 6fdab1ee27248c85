#pragma once
// Test support: renders a chessboard seen by a known pinhole camera with Brown-Conrady
// distortion, so calibration can be checked against the truth without real photos.
#include <opencv2/core.hpp>

#include <cstdint>
#include <utility>
#include <vector>

#include "svbtdf/calib/camera_calibration.h"

namespace svbtdf::calib::testing {

// Renders `board` (a chessboard: cols x rows inner corners) at pose (rvec, tvec in mm) into an
// 8-bit image, anti-aliased by 2x2 supersampling, with mild Gaussian noise when noise_sigma > 0.
cv::Mat RenderChessboard(const BoardSpec& board, const CameraModel& camera, const cv::Vec3d& rvec,
                         const cv::Vec3d& tvec, double noise_sigma, uint64_t seed);

// Board poses (rvec, tvec in mm) that tilt the board by up to ~35 degrees and move it around the
// frame of an 800 x 600 camera with f ~ 1000 px, seeded.
std::vector<std::pair<cv::Vec3d, cv::Vec3d>> VariedBoardPoses(int count, uint64_t seed);

}  // namespace svbtdf::calib::testing
