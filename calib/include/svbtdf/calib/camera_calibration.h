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

// A calibration target, the one vocabulary of board specifications (the CLI's --board, a
// session's rig.board.spec). Parsed from "chessboard:COLSxROWS:SQUARE_MM" (inner corners),
// "charuco:COLSxROWS:SQUARE_MM:MARKER_MM[:DICTIONARY]" (squares; dictionary default
// DICT_5X5_100), "circles:COLSxROWS:SPACING_MM" (OpenCV's symmetric circle grid, circles per row
// x rows, centres SPACING_MM apart) or "acircles:COLSxROWS:SPACING_MM" (OpenCV's asymmetric circle
// grid, e.g. its sample pattern acircles:4x11: circle (c, r) at ((2c + r % 2) SPACING_MM,
// r SPACING_MM), as OpenCV's calibration sample lays it out).
struct BoardSpec {
  enum class Kind { kChessboard, kCharuco, kSymmetricCircles, kAsymmetricCircles };
  Kind kind = Kind::kChessboard;
  int cols = 9;
  int rows = 6;
  double square_mm = 25.0;  // the square's side; for circle grids the spacing
  double marker_mm = 0.0;
  std::string dictionary = "DICT_5X5_100";

  // Throws svbtdf::Error(kInvalidInput) naming `argument` when the text is malformed.
  static BoardSpec Parse(const std::string& text, const std::string& argument = "--board");
  std::string ToString() const;
  // Board-frame coordinates (z = 0, millimetres) of every corner (circle centre) the detector can
  // report, by id.
  std::vector<cv::Point3f> CornerPositions() const;
  bool IsCircleGrid() const { return kind == Kind::kSymmetricCircles || kind == Kind::kAsymmetricCircles; }
};

// The corners found in one image.
struct BoardDetection {
  std::string source;  // the file (or capture key) the image came from
  bool found = false;
  std::string failure;  // why not, when !found
  std::vector<cv::Point2f> image_points;
  std::vector<cv::Point3f> object_points;
};

// Detects the board with sub-pixel corner refinement (circle grids: blob centroids, by
// cv::findCirclesGrid). `gray` is 8-bit single channel.
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

// How far a pixel's projection is uncertain because the intrinsics are (as mrcal reports it):
// the pixel is unprojected to its ray with the estimated intrinsics, and the ray projected again
// through the intrinsics' covariance -- sigma^2 (J^T J)^-1 of the whole fit (intrinsics and every
// view's pose), its intrinsics block, so the poses are marginalised and the parameters'
// correlations kept. Each figure is the standard deviation, in pixels, along the worst direction
// (the square root of the projection covariance's larger eigenvalue). Unlike mrcal's, the ray is
// held fixed in the camera frame (mrcal lets the camera's frame follow the board poses), so this
// is an upper bound for uses that do not care about the camera's rotation.
struct ProjectionUncertainty {
  double centre_px = 0.0;                       // at the image centre
  std::array<double, 4> corners_px = {0, 0, 0, 0};  // top-left, top-right, bottom-left, bottom-right
  double worst_px = 0.0;                        // largest over a 9 x 7 grid spanning the image
};

struct CalibrationReport {
  CameraModel camera;
  double rms_px = 0.0;  // over all used views
  std::array<double, 4> intrinsics_std = {0, 0, 0, 0};  // fx, fy, cx, cy
  std::array<double, 5> distortion_std = {0, 0, 0, 0, 0};
  ProjectionUncertainty projection_uncertainty;
  std::vector<ViewReport> views;
  // The model asked for: "full" or "centred" (CalibrationOptions::LensModel).
  std::string lens_model = "full";
  // Empty unless the full lens model was asked for and the narrow-lens model used instead (see
  // CalibrationOptions::max_principal_point_std_fraction): why.
  std::string narrow_lens_because;
  int used_views() const;
  // The model fitted: "narrow" when narrow_lens_because says why, else lens_model.
  std::string FittedLensModel() const { return narrow_lens_because.empty() ? lens_model : "narrow"; }
};

struct CalibrationOptions {
  // kFull: fx, fy, cx, cy, k1, k2, p1, p2, k3 (falling back to the narrow-lens model, see
  // max_principal_point_std_fraction). kCentred: square pixels, the principal point held at the
  // image centre, no tangential terms, k1 k2 k3 -- what OpenCV's calibration sample fits with
  // FIX_ASPECT_RATIO | FIX_PRINCIPAL_POINT | ZERO_TANGENT_DIST.
  enum class LensModel { kFull, kCentred };
  LensModel lens_model = LensModel::kFull;
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
