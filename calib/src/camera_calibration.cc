#include "svbtdf/calib/camera_calibration.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/aruco/charuco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <regex>
#include <sstream>

#include "svbtdf/common/error.h"
#include "svbtdf/common/statistics.h"

namespace svbtdf::calib {
namespace {

const std::map<std::string, int>& ArucoDictionaries() {
  static const std::map<std::string, int> dictionaries = {
      {"DICT_4X4_50", cv::aruco::DICT_4X4_50},     {"DICT_4X4_100", cv::aruco::DICT_4X4_100},
      {"DICT_4X4_250", cv::aruco::DICT_4X4_250},   {"DICT_5X5_50", cv::aruco::DICT_5X5_50},
      {"DICT_5X5_100", cv::aruco::DICT_5X5_100},   {"DICT_5X5_250", cv::aruco::DICT_5X5_250},
      {"DICT_6X6_50", cv::aruco::DICT_6X6_50},     {"DICT_6X6_100", cv::aruco::DICT_6X6_100},
      {"DICT_6X6_250", cv::aruco::DICT_6X6_250},   {"DICT_7X7_100", cv::aruco::DICT_7X7_100},
      {"DICT_ARUCO_ORIGINAL", cv::aruco::DICT_ARUCO_ORIGINAL},
  };
  return dictionaries;
}

cv::Ptr<cv::aruco::CharucoBoard> MakeCharucoBoard(const BoardSpec& board) {
  const auto dictionary = cv::aruco::getPredefinedDictionary(ArucoDictionaries().at(board.dictionary));
  return cv::aruco::CharucoBoard::create(board.cols, board.rows, static_cast<float>(board.square_mm),
                                         static_cast<float>(board.marker_mm), dictionary);
}

// Square pixels, the principal point at the image centre (OpenCV starts it there), k1 only.
constexpr int kNarrowLensFlags = cv::CALIB_FIX_ASPECT_RATIO | cv::CALIB_FIX_PRINCIPAL_POINT |
                                 cv::CALIB_ZERO_TANGENT_DIST | cv::CALIB_FIX_K2 | cv::CALIB_FIX_K3;

bool PrincipalPointIsUnobservable(const CalibrationReport& report, const CalibrationOptions& options) {
  const double limit = options.max_principal_point_std_fraction;
  if (limit <= 0) return false;
  return report.intrinsics_std[2] > limit * report.camera.width ||
         report.intrinsics_std[3] > limit * report.camera.height;
}

}  // namespace

BoardSpec BoardSpec::Parse(const std::string& text, const std::string& argument) {
  static const std::regex chessboard(R"(chessboard:(\d+)x(\d+):([0-9.]+))");
  static const std::regex charuco(R"(charuco:(\d+)x(\d+):([0-9.]+):([0-9.]+)(?::([A-Z0-9_]+))?)");
  static const std::regex circles(R"((a?circles):(\d+)x(\d+):([0-9.]+))");
  std::smatch m;
  BoardSpec board;
  try {
    if (std::regex_match(text, m, chessboard)) {
      board.kind = Kind::kChessboard;
      board.cols = std::stoi(m[1]);
      board.rows = std::stoi(m[2]);
      board.square_mm = std::stod(m[3]);
    } else if (std::regex_match(text, m, charuco)) {
      board.kind = Kind::kCharuco;
      board.cols = std::stoi(m[1]);
      board.rows = std::stoi(m[2]);
      board.square_mm = std::stod(m[3]);
      board.marker_mm = std::stod(m[4]);
      if (m[5].matched) board.dictionary = m[5];
    } else if (std::regex_match(text, m, circles)) {
      board.kind = m[1] == "acircles" ? Kind::kAsymmetricCircles : Kind::kSymmetricCircles;
      board.cols = std::stoi(m[2]);
      board.rows = std::stoi(m[3]);
      board.square_mm = std::stod(m[4]);
    } else {
      common::ThrowInvalidInput(argument, "cannot parse board '" + text + "'",
                        "use chessboard:COLSxROWS:SQUARE_MM (inner corners), "
                        "charuco:COLSxROWS:SQUARE_MM:MARKER_MM[:DICT], circles:COLSxROWS:SPACING_MM or "
                        "acircles:COLSxROWS:SPACING_MM");
    }
  } catch (const std::out_of_range&) {
    common::ThrowInvalidInput(argument, "a number in board '" + text + "' is out of range");
  }
  if (board.cols < 2 || board.rows < 2 || board.cols > 200 || board.rows > 200) {
    common::ThrowInvalidInput(argument, "the board needs 2 to 200 corners or squares per side, got '" + text + "'");
  }
  if (!(board.square_mm > 0)) {
    common::ThrowInvalidInput(argument, std::string(board.IsCircleGrid() ? "the circle spacing" : "the square size") +
                                            " must be > 0 mm, got '" + text + "'");
  }
  if (board.kind == Kind::kCharuco) {
    if (!(board.marker_mm > 0 && board.marker_mm < board.square_mm)) {
      common::ThrowInvalidInput(argument, "the marker must be smaller than the square");
    }
    if (!ArucoDictionaries().count(board.dictionary)) {
      common::ThrowInvalidInput(argument, "unknown ArUco dictionary '" + board.dictionary + "'", "e.g. DICT_5X5_100");
    }
  }
  return board;
}

std::string BoardSpec::ToString() const {
  static const std::map<Kind, std::string> prefixes = {{Kind::kChessboard, "chessboard:"},
                                                       {Kind::kCharuco, "charuco:"},
                                                       {Kind::kSymmetricCircles, "circles:"},
                                                       {Kind::kAsymmetricCircles, "acircles:"}};
  std::ostringstream out;
  out << prefixes.at(kind) << cols << "x" << rows << ":" << square_mm;
  if (kind == Kind::kCharuco) out << ":" << marker_mm << ":" << dictionary;
  return out.str();
}

std::vector<cv::Point3f> BoardSpec::CornerPositions() const {
  std::vector<cv::Point3f> corners;
  if (IsCircleGrid()) {
    // Row by row, as cv::findCirclesGrid reports the centres; an asymmetric grid's odd rows are
    // shifted by one spacing (OpenCV's calibration sample).
    for (int y = 0; y < rows; ++y) {
      for (int x = 0; x < cols; ++x) {
        const int column = kind == Kind::kAsymmetricCircles ? 2 * x + y % 2 : x;
        corners.emplace_back(static_cast<float>(column * square_mm), static_cast<float>(y * square_mm), 0.f);
      }
    }
    return corners;
  }
  // Chessboard: cols x rows inner corners. ChArUco: the (cols-1) x (rows-1) inner chessboard
  // corners, which OpenCV numbers row by row like this.
  const int nx = kind == Kind::kChessboard ? cols : cols - 1;
  const int ny = kind == Kind::kChessboard ? rows : rows - 1;
  const double offset = kind == Kind::kChessboard ? 0.0 : square_mm;
  for (int y = 0; y < ny; ++y) {
    for (int x = 0; x < nx; ++x) {
      corners.emplace_back(static_cast<float>(offset + x * square_mm), static_cast<float>(offset + y * square_mm), 0.f);
    }
  }
  return corners;
}

namespace {

// findChessboardCorners's time grows with the pixel count (about 4 s for a 24 MP frame), so the
// corners are looked for on a copy halved until its longer side is at most 2000 px, where
// squares of any usable board are still tens of pixels wide, and on the full image only if that
// fails. pyrDown keeps pixel i of the copy centred on pixel 2i of its source.
bool FindChessboardCorners(const cv::Mat& gray, const cv::Size& pattern, std::vector<cv::Point2f>* corners) {
  constexpr int kSearchSide = 2000;
  constexpr int kFlags = cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE | cv::CALIB_CB_FAST_CHECK;
  cv::Mat reduced = gray;
  float scale = 1.0f;
  while (std::max(reduced.cols, reduced.rows) > kSearchSide) {
    cv::pyrDown(reduced, reduced);
    scale *= 2.0f;
  }
  if (scale > 1.0f && cv::findChessboardCorners(reduced, pattern, *corners, kFlags)) {
    for (cv::Point2f& corner : *corners) corner *= scale;
    return true;
  }
  return cv::findChessboardCorners(gray, pattern, *corners, kFlags);
}

// OpenCV's default blob detector (what its calibration sample uses) first. It takes blobs of 25
// to 5000 px^2, and a grid photographed by a high-resolution camera has larger circles: then a
// detector whose largest blob is the circles' share of the image. The clustering search last: it
// copes with strong perspective and distortion where the default ordering fails.
bool FindCirclesGrid(const cv::Mat& gray, const BoardSpec& board, std::vector<cv::Point2f>* centres) {
  const int grid = board.kind == BoardSpec::Kind::kAsymmetricCircles ? cv::CALIB_CB_ASYMMETRIC_GRID
                                                                     : cv::CALIB_CB_SYMMETRIC_GRID;
  const cv::Size pattern(board.cols, board.rows);
  cv::SimpleBlobDetector::Params large;
  large.maxArea = std::max(large.maxArea, static_cast<float>(gray.total()) / static_cast<float>(board.cols * board.rows));
  for (const cv::SimpleBlobDetector::Params& params : {cv::SimpleBlobDetector::Params(), large}) {
    const cv::Ptr<cv::FeatureDetector> detector = cv::SimpleBlobDetector::create(params);
    if (cv::findCirclesGrid(gray, pattern, *centres, grid, detector)) return true;
  }
  const cv::Ptr<cv::FeatureDetector> detector = cv::SimpleBlobDetector::create(large);
  return cv::findCirclesGrid(gray, pattern, *centres, grid | cv::CALIB_CB_CLUSTERING, detector);
}

}  // namespace

BoardDetection DetectBoard(const cv::Mat& gray, const BoardSpec& board, const std::string& source) {
  BoardDetection detection;
  detection.source = source;
  if (gray.empty() || gray.type() != CV_8UC1) {
    detection.failure = "not an 8-bit single-channel image";
    return detection;
  }
  const std::vector<cv::Point3f> positions = board.CornerPositions();
  if (board.kind == BoardSpec::Kind::kChessboard) {
    std::vector<cv::Point2f> corners;
    if (!FindChessboardCorners(gray, cv::Size(board.cols, board.rows), &corners)) {
      detection.failure = "chessboard with " + std::to_string(board.cols) + "x" + std::to_string(board.rows) +
                          " inner corners not found";
      return detection;
    }
    // Refine within a window a bit smaller than half a square.
    cv::cornerSubPix(gray, corners, cv::Size(5, 5), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 50, 1e-4));
    detection.image_points = corners;
    detection.object_points = positions;
  } else if (board.IsCircleGrid()) {
    std::vector<cv::Point2f> centres;
    if (!FindCirclesGrid(gray, board, &centres)) {
      detection.failure = board.ToString().substr(0, board.ToString().find(':')) + " grid of " +
                          std::to_string(board.cols) + "x" + std::to_string(board.rows) + " circles not found";
      return detection;
    }
    detection.image_points = centres;
    detection.object_points = positions;
  } else {
    const auto charuco = MakeCharucoBoard(board);
    std::vector<int> marker_ids;
    std::vector<std::vector<cv::Point2f>> marker_corners;
    cv::aruco::detectMarkers(gray, charuco->dictionary, marker_corners, marker_ids);
    if (marker_ids.size() < 4) {
      detection.failure = "only " + std::to_string(marker_ids.size()) + " ArUco markers found";
      return detection;
    }
    std::vector<cv::Point2f> corners;
    std::vector<int> ids;
    cv::aruco::interpolateCornersCharuco(marker_corners, marker_ids, gray, charuco, corners, ids);
    if (ids.size() < 6) {
      detection.failure = "only " + std::to_string(ids.size()) + " ChArUco corners found";
      return detection;
    }
    for (size_t k = 0; k < ids.size(); ++k) {
      detection.image_points.push_back(corners[k]);
      detection.object_points.push_back(positions.at(ids[k]));
    }
  }
  detection.found = true;
  return detection;
}

cv::Mat CameraModel::CameraMatrix() const {
  return (cv::Mat_<double>(3, 3) << fx, 0, cx, 0, fy, cy, 0, 0, 1);
}

cv::Mat CameraModel::DistortionCoefficients() const {
  return (cv::Mat_<double>(1, 5) << distortion[0], distortion[1], distortion[2], distortion[3], distortion[4]);
}

int CalibrationReport::used_views() const {
  return static_cast<int>(std::count_if(views.begin(), views.end(), [](const ViewReport& v) { return v.used; }));
}

namespace {

// The free intrinsics of a fit with OpenCV's `flags`, as a 9 x k matrix whose columns say how each
// moves the nine (fx, fy, cx, cy, k1, k2, p1, p2, k3) that cv::projectPoints differentiates.
cv::Mat FreeIntrinsics(int flags, double aspect_ratio) {
  std::vector<cv::Mat> columns;
  const auto column = [&columns](std::initializer_list<std::pair<int, double>> entries) {
    cv::Mat c = cv::Mat::zeros(9, 1, CV_64F);
    for (const auto& [row, value] : entries) c.at<double>(row) = value;
    columns.push_back(c);
  };
  if (flags & cv::CALIB_FIX_ASPECT_RATIO) {
    column({{0, aspect_ratio}, {1, 1.0}});  // fx = aspect fy: one parameter
  } else {
    column({{0, 1.0}});
    column({{1, 1.0}});
  }
  if (!(flags & cv::CALIB_FIX_PRINCIPAL_POINT)) {
    column({{2, 1.0}});
    column({{3, 1.0}});
  }
  if (!(flags & cv::CALIB_FIX_K1)) column({{4, 1.0}});
  if (!(flags & cv::CALIB_FIX_K2)) column({{5, 1.0}});
  if (!(flags & cv::CALIB_ZERO_TANGENT_DIST)) {
    column({{6, 1.0}});
    column({{7, 1.0}});
  }
  if (!(flags & cv::CALIB_FIX_K3)) column({{8, 1.0}});
  cv::Mat selection;
  cv::hconcat(columns, selection);
  return selection;
}

// The data of the final fit that the uncertainty is propagated from.
struct FittedViews {
  std::vector<std::vector<cv::Point3f>> object_points;
  std::vector<std::vector<cv::Point2f>> image_points;
  std::vector<cv::Mat> rvecs, tvecs;
  int flags = 0;
};

// sigma^2 (J^T J)^-1 of the whole fit, its block of the free intrinsics (FreeIntrinsics' order).
// sigma^2 is estimated as OpenCV does for its stdDeviationsIntrinsics (the squared residuals over
// the number of points, not of residuals, less the parameters: about twice the unbiased estimate,
// so conservative by about sqrt(2)), so that the block's diagonal gives back OpenCV's standard
// deviations, which calibration.json reports beside it.
cv::Mat IntrinsicsCovariance(const FittedViews& fit, const CameraModel& camera, const cv::Mat& selection) {
  const int k = selection.cols;
  const int views = static_cast<int>(fit.object_points.size());
  cv::Mat normal = cv::Mat::zeros(k + 6 * views, k + 6 * views, CV_64F);
  double squared_residuals = 0.0;
  int points = 0;
  for (int v = 0; v < views; ++v) {
    std::vector<cv::Point2f> projected;
    cv::Mat jacobian;  // 2n x 15: rvec, tvec, fx fy, cx cy, five distortion terms
    cv::projectPoints(fit.object_points[v], fit.rvecs[v], fit.tvecs[v], camera.CameraMatrix(),
                      camera.DistortionCoefficients(), projected, jacobian);
    const cv::Mat intrinsics = jacobian.colRange(6, 15) * selection;
    const cv::Mat pose = jacobian.colRange(0, 6);
    const cv::Rect pose_block(k + 6 * v, k + 6 * v, 6, 6);
    normal(cv::Rect(0, 0, k, k)) += intrinsics.t() * intrinsics;
    normal(cv::Rect(k + 6 * v, 0, 6, k)) += intrinsics.t() * pose;
    normal(cv::Rect(0, k + 6 * v, k, 6)) += pose.t() * intrinsics;
    normal(pose_block) += pose.t() * pose;
    for (size_t p = 0; p < projected.size(); ++p) {
      const cv::Point2f d = projected[p] - fit.image_points[v][p];
      squared_residuals += d.dot(d);
    }
    points += static_cast<int>(projected.size());
  }
  const int dof = std::max(points - normal.rows, 1);
  const cv::Mat inverse = normal.inv(cv::DECOMP_SVD);
  return inverse(cv::Rect(0, 0, k, k)) * (squared_residuals / dof);
}

// The worst-direction standard deviation of pixel `pixel`'s projection (ProjectionUncertainty).
double ProjectionStdAt(const cv::Point2d& pixel, const CameraModel& camera, const cv::Mat& selection,
                       const cv::Mat& covariance) {
  std::vector<cv::Point2d> normalised;
  cv::undistortPoints(std::vector<cv::Point2d>{pixel}, normalised, camera.CameraMatrix(),
                      camera.DistortionCoefficients());
  const std::vector<cv::Point3d> ray = {{normalised[0].x, normalised[0].y, 1.0}};
  std::vector<cv::Point2d> projected;
  cv::Mat jacobian;
  cv::projectPoints(ray, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), camera.CameraMatrix(),
                    camera.DistortionCoefficients(), projected, jacobian);
  const cv::Mat along = jacobian.colRange(6, 15) * selection;
  const cv::Mat projection_covariance = along * covariance * along.t();
  cv::Mat eigenvalues;
  cv::eigen(projection_covariance, eigenvalues);
  return std::sqrt(std::max(eigenvalues.at<double>(0), 0.0));
}

ProjectionUncertainty EstimateProjectionUncertainty(const FittedViews& fit, const CameraModel& camera) {
  const cv::Mat selection = FreeIntrinsics(fit.flags, camera.fx / camera.fy);
  const cv::Mat covariance = IntrinsicsCovariance(fit, camera, selection);
  const double right = camera.width - 1.0, bottom = camera.height - 1.0;
  ProjectionUncertainty u;
  u.centre_px = ProjectionStdAt({right / 2, bottom / 2}, camera, selection, covariance);
  const std::array<cv::Point2d, 4> corners = {{{0, 0}, {right, 0}, {0, bottom}, {right, bottom}}};
  for (int c = 0; c < 4; ++c) u.corners_px[c] = ProjectionStdAt(corners[c], camera, selection, covariance);
  for (int y = 0; y < 7; ++y) {
    for (int x = 0; x < 9; ++x) {
      const cv::Point2d pixel(right * x / 8.0, bottom * y / 6.0);
      u.worst_px = std::max(u.worst_px, ProjectionStdAt(pixel, camera, selection, covariance));
    }
  }
  return u;
}

int InitialFlags(const CalibrationOptions& options) {
  int flags = options.fix_k3 ? cv::CALIB_FIX_K3 : 0;
  if (options.lens_model == CalibrationOptions::LensModel::kCentred) {
    flags |= cv::CALIB_FIX_ASPECT_RATIO | cv::CALIB_FIX_PRINCIPAL_POINT | cv::CALIB_ZERO_TANGENT_DIST;
  }
  return flags;
}

}  // namespace

CalibrationReport CalibrateCamera(const std::vector<BoardDetection>& detections, cv::Size image_size,
                                  const CalibrationOptions& options) {
  CalibrationReport report;
  std::vector<int> candidates;  // indices into detections still in play
  for (size_t k = 0; k < detections.size(); ++k) {
    ViewReport view;
    view.source = detections[k].source;
    if (!detections[k].found) {
      view.dropped_because = detections[k].failure.empty() ? "board not found" : detections[k].failure;
    } else {
      candidates.push_back(static_cast<int>(k));
    }
    report.views.push_back(view);
  }
  const bool centred = options.lens_model == CalibrationOptions::LensModel::kCentred;
  report.lens_model = centred ? "centred" : "full";
  int flags = InitialFlags(options);
  for (int round = 0;; ++round) {
    if (static_cast<int>(candidates.size()) < options.min_views) {
      common::ThrowInvalidInput("calibration images",
                        "only " + std::to_string(candidates.size()) + " usable board views, " +
                            std::to_string(options.min_views) + " needed",
                        "add views of the board at varied angles filling the frame");
    }
    FittedViews fit;
    fit.flags = flags;
    for (int k : candidates) {
      fit.object_points.push_back(detections[k].object_points);
      fit.image_points.push_back(detections[k].image_points);
    }
    cv::Mat camera_matrix, distortion, std_intrinsics, std_extrinsics, per_view_errors;
    report.rms_px = cv::calibrateCamera(fit.object_points, fit.image_points, image_size, camera_matrix, distortion,
                                        fit.rvecs, fit.tvecs, std_intrinsics, std_extrinsics, per_view_errors, flags);
    std::vector<double> errors(per_view_errors.begin<double>(), per_view_errors.end<double>());
    const double threshold = std::max(options.outlier_factor * common::Median(errors), options.outlier_floor_px);
    std::vector<int> kept;
    for (size_t j = 0; j < candidates.size(); ++j) {
      ViewReport& view = report.views[candidates[j]];
      view.rms_px = errors[j];
      if (errors[j] > threshold && round < 3) {
        std::ostringstream reason;
        reason << "reprojection RMS " << errors[j] << " px is an outlier (threshold " << threshold << " px)";
        view.dropped_because = reason.str();
        view.used = false;
      } else {
        view.used = true;
        view.rvec = fit.rvecs[j];
        view.tvec = fit.tvecs[j];
        kept.push_back(candidates[j]);
      }
    }
    if (kept.size() == candidates.size()) {
      CameraModel& camera = report.camera;
      camera.width = image_size.width;
      camera.height = image_size.height;
      camera.fx = camera_matrix.at<double>(0, 0);
      camera.fy = camera_matrix.at<double>(1, 1);
      camera.cx = camera_matrix.at<double>(0, 2);
      camera.cy = camera_matrix.at<double>(1, 2);
      for (int c = 0; c < 5; ++c) camera.distortion[c] = distortion.at<double>(0, c);
      for (int c = 0; c < 4; ++c) report.intrinsics_std[c] = std_intrinsics.at<double>(c, 0);
      for (int c = 0; c < 5; ++c) report.distortion_std[c] = std_intrinsics.at<double>(4 + c, 0);
      // With the aspect ratio fixed OpenCV estimates fy alone (fx = fy) and reports no spread for fx.
      if (flags & cv::CALIB_FIX_ASPECT_RATIO) report.intrinsics_std[0] = report.intrinsics_std[1];
      if (!centred && report.narrow_lens_because.empty() && PrincipalPointIsUnobservable(report, options)) {
        std::ostringstream reason;
        reason.precision(3);
        reason << "the full model's principal point is uncertain by (" << report.intrinsics_std[2] << ", "
               << report.intrinsics_std[3] << ") px, over " << 100 * options.max_principal_point_std_fraction
               << "% of the image";
        report.narrow_lens_because = reason.str();
        flags = kNarrowLensFlags;
        continue;  // refit the same views with the narrow-lens model
      }
      report.projection_uncertainty = EstimateProjectionUncertainty(fit, camera);
      return report;
    }
    candidates = kept;
  }
}

nlohmann::json ToJson(const CalibrationReport& report) {
  const CameraModel& c = report.camera;
  nlohmann::json views = nlohmann::json::array();
  for (const ViewReport& v : report.views) {
    nlohmann::json view = {{"source", v.source}, {"used", v.used}, {"rms_px", v.rms_px}};
    if (!v.used) view["dropped_because"] = v.dropped_because;
    if (v.used) {
      view["rvec"] = {v.rvec[0], v.rvec[1], v.rvec[2]};
      view["tvec_mm"] = {v.tvec[0], v.tvec[1], v.tvec[2]};
    }
    views.push_back(view);
  }
  return {{"width", c.width},
          {"height", c.height},
          {"fx", c.fx},
          {"fy", c.fy},
          {"cx", c.cx},
          {"cy", c.cy},
          {"distortion", {c.distortion[0], c.distortion[1], c.distortion[2], c.distortion[3], c.distortion[4]}},
          {"rms_px", report.rms_px},
          {"std", {{"fx", report.intrinsics_std[0]}, {"fy", report.intrinsics_std[1]},
                   {"cx", report.intrinsics_std[2]}, {"cy", report.intrinsics_std[3]},
                   {"distortion", report.distortion_std}}},
          {"projection_uncertainty_px",
           {{"centre", report.projection_uncertainty.centre_px},
            {"corners", report.projection_uncertainty.corners_px},
            {"worst", report.projection_uncertainty.worst_px}}},
          {"lens_model", report.FittedLensModel()},
          {"lens_model_because", report.narrow_lens_because},
          {"views_used", report.used_views()},
          {"views", views}};
}

}  // namespace svbtdf::calib
