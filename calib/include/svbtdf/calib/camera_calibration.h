#pragma once
// Zhang camera calibration with OpenCV, for the rig's camera and for any folder of board photos.
// Views whose board is not found, or whose reprojection error is an outlier, are reported and
// dropped, never silently used; the report carries the RMS and per-view errors and the standard
// deviations of the estimated parameters.

#include <array>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>
#include <opencv2/core.hpp>

namespace svbtdf::calib {

// A calibration target. Parsed from "chessboard:COLSxROWS:SQUARE_MM" (inner corners) or
// "charuco:COLSxROWS:SQUARE_MM:MARKER_MM[:DICTIONARY]" (squares; dictionary default DICT_5X5_100).
struct BoardSpec {
  enum class Kind { kChessboard, kCharuco };
  Kind kind = Kind::kChessboard;
  int cols = 9;
  int rows = 6;
  double square_mm = 25.0;
  double marker_mm = 0.0;
  std::string dictionary = "DICT_5X5_100";

  // Throws svbtdf::Error(kInvalidInput) naming `argument` when the text is malformed.
  static BoardSpec Parse(const std::string& text, const std::string& argument = "--board");
  std::string ToString() const;
  // Board-frame coordinates (z = 0, millimetres) of every corner the detector can report, by id.
  std::vector<cv::Point3f> CornerPositions() const;
};

// The corners found in one image.
struct BoardDetection {
  std::string source;  // the file (or capture key) the image came from
  bool found = false;
  std::string failure;  // why not, when !found
  std::vector<cv::Point2f> image_points;
  std::vector<cv::Point3f> object_points;
};

// Detects the board with sub-pixel corner refinement. `gray` is 8-bit single channel.
BoardDetection DetectBoard(const cv::Mat& gray, const BoardSpec& board, const std::string& source);

// Pinhole camera with OpenCV's five-parameter Brown-Conrady distortion (k1 k2 p1 p2 k3).
struct CameraModel {
  int width = 0, height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  std::array<double, 5> distortion = {0, 0, 0, 0, 0};
  cv::Mat CameraMatrix() const;
  cv::Mat DistortionCoefficients() const;
};

struct ViewReport {
  std::string source;
  bool used = false;
  std::string dropped_because;  // empty when used
  double rms_px = 0.0;          // reprojection RMS of this view (0 when the board was not found)
  cv::Vec3d rvec, tvec;         // board pose in the camera frame (mm), when used
};

struct CalibrationReport {
  CameraModel camera;
  double rms_px = 0.0;  // over all used views
  std::array<double, 4> intrinsics_std = {0, 0, 0, 0};  // fx, fy, cx, cy
  std::array<double, 5> distortion_std = {0, 0, 0, 0, 0};
  std::vector<ViewReport> views;
  // Empty when the full lens model was estimated; otherwise why the narrow-lens model was used
  // instead (see CalibrationOptions::max_principal_point_std_fraction).
  std::string narrow_lens_because;
  int used_views() const;
};

struct CalibrationOptions {
  // A view is an outlier when its RMS exceeds max(outlier_factor * median RMS, outlier_floor_px).
  double outlier_factor = 3.0;
  double outlier_floor_px = 0.5;
  int min_views = 3;
  bool fix_k3 = false;  // hold k3 at 0 (wise with few views or a narrow lens)
  // A long lens cannot tell a shifted principal point from a rotated camera, nor a changed focal
  // length from a board further away: the full model (fx, fy, cx, cy, k1, k2, p1, p2, k3) is then
  // ill-determined, its principal point drifting by tens of pixels and dragging the poses with
  // it. When the principal point's standard deviation exceeds this fraction of the image size,
  // the views are refitted with the narrow-lens model instead: square pixels, the principal point
  // at the image centre, k1 only (COLMAP's SIMPLE_RADIAL, what it uses for such lenses). A real
  // lens's principal point is a few pixels from the centre; the free estimate was further off.
  // 0 keeps the full model whatever the views.
  double max_principal_point_std_fraction = 0.02;
};

// Calibrates from the detections (failed ones are reported as dropped). Throws
// svbtdf::Error(kInvalidInput) when fewer than `min_views` boards are usable.
CalibrationReport CalibrateCamera(const std::vector<BoardDetection>& detections, cv::Size image_size,
                                  const CalibrationOptions& options = {});

// JSON with the keys of calibration.json's "camera" block: fx, fy, cx, cy, distortion, rms_px,
// width, height, the standard deviations and the per-view report.
nlohmann::json ToJson(const CalibrationReport& report);

}  // namespace svbtdf::calib
