#include "svbtdf/calib/camera_calibration.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/aruco/charuco.hpp>
#include <opencv2/calib3d.hpp>
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
    } else {
      common::ThrowInvalidInput(argument, "cannot parse board '" + text + "'",
                        "use chessboard:COLSxROWS:SQUARE_MM (inner corners) or "
                        "charuco:COLSxROWS:SQUARE_MM:MARKER_MM[:DICT]");
    }
  } catch (const std::out_of_range&) {
    common::ThrowInvalidInput(argument, "a number in board '" + text + "' is out of range");
  }
  if (board.cols < 2 || board.rows < 2 || board.cols > 200 || board.rows > 200) {
    common::ThrowInvalidInput(argument, "the board needs 2 to 200 corners or squares per side, got '" + text + "'");
  }
  if (!(board.square_mm > 0)) common::ThrowInvalidInput(argument, "the square size must be > 0 mm");
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
  std::ostringstream out;
  out << (kind == Kind::kChessboard ? "chessboard:" : "charuco:") << cols << "x" << rows << ":" << square_mm;
  if (kind == Kind::kCharuco) out << ":" << marker_mm << ":" << dictionary;
  return out.str();
}

std::vector<cv::Point3f> BoardSpec::CornerPositions() const {
  // Chessboard: cols x rows inner corners. ChArUco: the (cols-1) x (rows-1) inner chessboard
  // corners, which OpenCV numbers row by row like this.
  const int nx = kind == Kind::kChessboard ? cols : cols - 1;
  const int ny = kind == Kind::kChessboard ? rows : rows - 1;
  const double offset = kind == Kind::kChessboard ? 0.0 : square_mm;
  std::vector<cv::Point3f> corners;
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
  int flags = options.fix_k3 ? cv::CALIB_FIX_K3 : 0;
  for (int round = 0;; ++round) {
    if (static_cast<int>(candidates.size()) < options.min_views) {
      common::ThrowInvalidInput("calibration images",
                        "only " + std::to_string(candidates.size()) + " usable board views, " +
                            std::to_string(options.min_views) + " needed",
                        "add views of the board at varied angles filling the frame");
    }
    std::vector<std::vector<cv::Point3f>> object_points;
    std::vector<std::vector<cv::Point2f>> image_points;
    for (int k : candidates) {
      object_points.push_back(detections[k].object_points);
      image_points.push_back(detections[k].image_points);
    }
    cv::Mat camera_matrix, distortion, std_intrinsics, std_extrinsics, per_view_errors;
    std::vector<cv::Mat> rvecs, tvecs;
    report.rms_px = cv::calibrateCamera(object_points, image_points, image_size, camera_matrix, distortion, rvecs,
                                        tvecs, std_intrinsics, std_extrinsics, per_view_errors, flags);
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
        view.rvec = rvecs[j];
        view.tvec = tvecs[j];
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
      if (report.narrow_lens_because.empty() && PrincipalPointIsUnobservable(report, options)) {
        std::ostringstream reason;
        reason.precision(3);
        reason << "the full model's principal point is uncertain by (" << report.intrinsics_std[2] << ", "
               << report.intrinsics_std[3] << ") px, over " << 100 * options.max_principal_point_std_fraction
               << "% of the image";
        report.narrow_lens_because = reason.str();
        flags = kNarrowLensFlags;
        continue;  // refit the same views with the narrow-lens model
      }
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
          {"lens_model", report.narrow_lens_because.empty() ? "full" : "narrow"},
          {"lens_model_because", report.narrow_lens_because},
          {"views_used", report.used_views()},
          {"views", views}};
}

}  // namespace svbtdf::calib
