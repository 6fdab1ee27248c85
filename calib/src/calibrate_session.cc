#include "svbtdf/calib/calibrate_session.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>

#include "svbtdf/calib/dot_identification.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/progress.h"

namespace svbtdf::calib {
namespace {

std::string ImageFile(const session::Session& session, const std::string& key) {
  return (session.folder() / session.Entry(key).file).string();
}

double MaxDn(int bits) { return std::ldexp(1.0, bits) - 1.0; }

// The mean of the channels as float, checked for size.
cv::Mat GrayImage(const session::Session& session, const std::string& key, const cv::Size& expected) {
  if (!session.Contains(key)) {
    common::ThrowInvalidInput(session.folder().string(), "has no image '" + key + "'", "complete the capture first");
  }
  const common::CameraImage image = session.ReadImage(key);
  if (!expected.empty() && (image.width != expected.width || image.height != expected.height)) {
    common::ThrowFormatError(ImageFile(session, key), "is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                                                  " pixels but the session's camera is " + std::to_string(expected.width) +
                                                  "x" + std::to_string(expected.height));
  }
  cv::Mat gray(image.height, image.width, CV_32F);
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      float sum = 0;
      for (int c = 0; c < image.channels; ++c) sum += image.at(x, y, c);
      gray.at<float>(y, x) = sum / image.channels;
    }
  }
  return gray;
}

cv::Mat ToEightBit(const cv::Mat& gray, int bits) {
  cv::Mat eight;
  gray.convertTo(eight, CV_8U, 255.0 / MaxDn(bits));
  return eight;
}

CalibrationReport CalibrateCameraFromBoards(const session::Session& session, const BoardSpec& board, const cv::Size& size,
                                            int bits, const CalibrateSessionOptions& options) {
  const std::vector<std::string> keys = session.PlannedKeys(session::CaptureKind::kBoardView);
  std::vector<BoardDetection> detections;
  std::unique_ptr<common::ProgressBar> progress;
  if (options.progress) progress = std::make_unique<common::ProgressBar>("detecting boards", static_cast<int64_t>(keys.size()), "images");
  for (const std::string& key : keys) {
    detections.push_back(DetectBoard(ToEightBit(GrayImage(session, key, size), bits), board, key));
    if (progress) progress->Advance();
  }
  if (progress) progress->Finish();
  return CalibrateCamera(detections, size, options.camera);
}

// The pose of the sample frame from the board in the holder. The board is centred on the sample
// with its x axis along the sample's x and its y axis along the sample's -y (it faces the camera);
// OpenCV may number the corners from either end, which turns the pose by 180 degrees about the
// normal: the camera is on the sample's -y side (docs/calibration-format.md) decides.
SamplePlane SamplePlaneFromBoard(const session::Session& session, const BoardSpec& board, const CameraModel& camera, int bits) {
  const std::vector<std::string> keys = session.PlannedKeys(session::CaptureKind::kSamplePlaneView);
  if (keys.empty()) common::ThrowInvalidInput(session.folder().string(), "plans no sample_plane/ capture (the board in the sample holder)");
  const cv::Size size(camera.width, camera.height);
  const BoardDetection detection = DetectBoard(ToEightBit(GrayImage(session, keys.front(), size), bits), board, keys.front());
  if (!detection.found) {
    common::ThrowFormatError(ImageFile(session, keys.front()), "shows no " + board.ToString() + " board: " + detection.failure,
                     "the board must lie flat in the sample holder, fully in view");
  }
  // Board corner (i, j) -> sample frame (i s - cx, cy - j s, 0), centred on the inner corners.
  double max_x = 0, max_y = 0;
  for (const cv::Point3f& p : detection.object_points) max_x = std::max<double>(max_x, p.x), max_y = std::max<double>(max_y, p.y);
  std::vector<cv::Point3d> sample_points;
  for (const cv::Point3f& p : detection.object_points) {
    sample_points.emplace_back((p.x - max_x / 2) / 1000.0, (max_y / 2 - p.y) / 1000.0, 0.0);
  }
  SamplePlane plane;
  for (int attempt = 0; attempt < 2; ++attempt) {
    std::vector<cv::Point2f> image_points = detection.image_points;
    if (attempt == 1) std::reverse(image_points.begin(), image_points.end());
    cv::Vec3d rvec, tvec;
    cv::solvePnP(sample_points, image_points, camera.CameraMatrix(), camera.DistortionCoefficients(), rvec, tvec, false,
                 cv::SOLVEPNP_IPPE);
    cv::Mat rotation;
    cv::Rodrigues(rvec, rotation);
    cv::cv2eigen(rotation, plane.rotation);
    plane.translation = model::Vec3(tvec[0], tvec[1], tvec[2]);
    std::vector<cv::Point2d> reprojected;
    cv::projectPoints(sample_points, rvec, tvec, camera.CameraMatrix(), camera.DistortionCoefficients(), reprojected);
    double sum = 0;
    for (size_t k = 0; k < reprojected.size(); ++k) {
      sum += std::pow(cv::norm(cv::Point2d(image_points[k]) - reprojected[k]), 2);
    }
    plane.rms_px = std::sqrt(sum / reprojected.size());
    const model::Vec3 camera_centre = plane.CameraCentre();
    if (camera_centre.z() > 0 && camera_centre.y() < 0) return plane;
  }
  common::ThrowFormatError(ImageFile(session, keys.front()), "gives a sample-plane pose with the camera not above the sample's -y side",
                   "lay the board in the holder with its rows along the sample's x axis");
}

// Blobs brighter than a fifth of the way from the background to the peak. Each centroid weighs
// the brightness above the background over the blob's box grown by half its size (pixels of
// other blobs excepted), not over the thresholded pixels alone: those depend on the threshold,
// which one bright speck elsewhere raises, and a dot seen obliquely is not symmetric about its
// peak, so the centroid of its brightest core moves.
std::vector<Eigen::Vector2d> FindBlobs(const cv::Mat& gray) {
  std::vector<float> values(gray.begin<float>(), gray.end<float>());
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  const double background = values[values.size() / 2];
  double peak = 0;
  cv::minMaxLoc(gray, nullptr, &peak);
  const double threshold = background + 0.2 * (peak - background);
  cv::Mat mask = gray > threshold, labels, stats, centroids;
  const int count = cv::connectedComponentsWithStats(mask, labels, stats, centroids, 8, CV_32S);
  std::vector<Eigen::Vector2d> blobs;
  for (int label = 1; label < count; ++label) {
    const int w = stats.at<int>(label, cv::CC_STAT_WIDTH), h = stats.at<int>(label, cv::CC_STAT_HEIGHT);
    const int grow = std::max(2, std::max(w, h) / 2);
    const int x0 = std::max(0, stats.at<int>(label, cv::CC_STAT_LEFT) - grow);
    const int y0 = std::max(0, stats.at<int>(label, cv::CC_STAT_TOP) - grow);
    const int x1 = std::min(gray.cols, stats.at<int>(label, cv::CC_STAT_LEFT) + w + grow);
    const int y1 = std::min(gray.rows, stats.at<int>(label, cv::CC_STAT_TOP) + h + grow);
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();  // (w x, w y, w)
    for (int y = y0; y < y1; ++y) {
      for (int x = x0; x < x1; ++x) {
        const int other = labels.at<int>(y, x);
        if (other != 0 && other != label) continue;
        const double weight = std::max(0.0, gray.at<float>(y, x) - background);
        sum += Eigen::Vector3d(weight * x, weight * y, weight);
      }
    }
    if (sum.z() > 0) blobs.emplace_back(sum.x() / sum.z(), sum.y() / sum.z());
  }
  return blobs;
}

// The direction (sample frame, not unit) of the camera ray through `pixel`.
model::Vec3 PixelRay(const Eigen::Vector2d& pixel, const CameraModel& camera, const SamplePlane& plane) {
  std::vector<cv::Point2d> in = {{pixel.x(), pixel.y()}}, out;
  cv::undistortPoints(in, out, camera.CameraMatrix(), camera.DistortionCoefficients());
  return plane.rotation.transpose() * model::Vec3(out[0].x, out[0].y, 1.0);
}

// Where the camera ray through `pixel` meets the plane z = z0 of the sample frame.
model::Vec3 BackProject(const Eigen::Vector2d& pixel, const CameraModel& camera, const SamplePlane& plane, double z0) {
  const model::Vec3 direction = PixelRay(pixel, camera, plane);
  const model::Vec3 origin = plane.CameraCentre();
  return origin + direction * ((z0 - origin.z()) / direction.z());
}

// How far (mm) the ray through a dot's centroid meets the monitor plane (through `position`, with
// `normal`) from where the fitted grid puts the dot.
double DotResidualMm(const Eigen::Vector2d& pixel, const model::Vec3& position, const model::Vec3& normal, const CameraModel& camera,
                     const SamplePlane& plane) {
  const model::Vec3 centre = plane.CameraCentre();
  const model::Vec3 direction = PixelRay(pixel, camera, plane);
  const double t = normal.dot(position - centre) / normal.dot(direction);
  return 1000.0 * (centre + t * direction - position).norm();
}

// What the session says it displayed (docs/session-format.md, rig.monitor and rig.dots).
struct NominalDots {
  DisplayedGrid grid;  // the dots' centres in monitor pixels and the fiducial dots
  double radius_px = 0, distance_m = 0.04;
  std::optional<double> orientation_deg;  // rig.monitor.orientation_deg, as the lab noted it
};

NominalDots ReadNominalDots(const session::Session& session) {
  const std::string source = (session.folder() / "session.json").string();
  NominalDots n;
  DisplayedGrid& grid = n.grid;
  const session::RigDescription& rig = session.rig();
  grid.pixel_pitch_m = rig.monitor.pixel_pitch_m;
  n.distance_m = rig.monitor.distance_m;
  if (!std::isnan(rig.monitor.orientation_deg)) n.orientation_deg = rig.monitor.orientation_deg;
  n.radius_px = rig.dots.radius_px;
  // Monitor pixel (i, j) covers [i, i + 1) x [j, j + 1): a dot drawn on it is centred on (i + 0.5, j + 0.5).
  for (const auto& [x, y] : rig.dots.positions_px) grid.monitor_px.emplace_back(x + 0.5, y + 0.5);
  const std::vector<int> fiducials = rig.dots.fiducials.value_or(std::vector<int>{});
  if (grid.monitor_px.size() < 4 || !(grid.pixel_pitch_m > 0) || !(n.distance_m > 0) || !(n.radius_px > 0)) {
    common::ThrowFormatError(source, "does not describe the monitor and dots: it needs at least 4 dots "
                             "(rig.dots.positions_px), their radius (rig.dots.radius_px), a positive monitor pixel "
                             "pitch (rig.monitor.pixel_pitch_m) and distance (rig.monitor.distance_m)");
  }
  if (!fiducials.empty()) {
    grid.fiducial.assign(grid.monitor_px.size(), false);
    for (int q : fiducials) {
      if (q < 0 || q >= static_cast<int>(grid.monitor_px.size())) {
        common::ThrowFormatError(source, "lists fiducial dot " + std::to_string(q) + " of " +
                                     std::to_string(grid.monitor_px.size()) + " (rig.dots.fiducials)");
      }
      grid.fiducial[q] = true;
    }
  }
  grid.spacing_m = std::numeric_limits<double>::infinity();
  for (size_t a = 0; a < grid.monitor_px.size(); ++a) {
    for (size_t b = a + 1; b < grid.monitor_px.size(); ++b) {
      grid.spacing_m = std::min(grid.spacing_m, (grid.monitor_px[a] - grid.monitor_px[b]).norm() * grid.pixel_pitch_m);
    }
  }
  if (!(grid.spacing_m > 0)) common::ThrowFormatError(source, "lists two dots at the same position (rig.dots.positions_px)");
  return n;
}

// The brightness above the background within `radius` pixels of each blob centre, per second of
// exposure.
std::vector<double> BlobSignals(const cv::Mat& gray, const std::vector<Eigen::Vector2d>& blobs, double radius,
                                double exposure_s) {
  std::vector<float> values(gray.begin<float>(), gray.end<float>());
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  const double background = values[values.size() / 2];
  std::vector<double> signals;
  const int r = static_cast<int>(std::ceil(radius));
  for (const Eigen::Vector2d& b : blobs) {
    double sum = 0;
    const int cx = static_cast<int>(std::lround(b.x())), cy = static_cast<int>(std::lround(b.y()));
    for (int y = std::max(0, cy - r); y <= std::min(gray.rows - 1, cy + r); ++y) {
      for (int x = std::max(0, cx - r); x <= std::min(gray.cols - 1, cx + r); ++x) {
        if (std::hypot(x - b.x(), y - b.y()) <= radius) sum += std::max(0.0, gray.at<float>(y, x) - background);
      }
    }
    signals.push_back(sum / exposure_s);
  }
  return signals;
}

// Which all-dots blobs the fiducial capture shows lit: those keeping at least half of their
// all-dots signal (the same dots at the same exposure give the same signal).
std::vector<bool> FiducialBlobs(const session::Session& session, const std::string& all_dots_key, const cv::Mat& all_dots,
                                const std::vector<Eigen::Vector2d>& blobs, const cv::Size& size) {
  const std::vector<std::string> keys = session.PlannedKeys(session::CaptureKind::kFiducials);
  if (keys.empty() || blobs.size() < 2) return {};
  const cv::Mat fiducial = GrayImage(session, keys.front(), size);
  // Half the distance to the nearest other blob: each window holds one dot.
  std::vector<double> nearest;
  for (size_t a = 0; a < blobs.size(); ++a) {
    double best = std::numeric_limits<double>::infinity();
    for (size_t b = 0; b < blobs.size(); ++b) {
      if (a != b) best = std::min(best, (blobs[a] - blobs[b]).norm());
    }
    nearest.push_back(best);
  }
  std::nth_element(nearest.begin(), nearest.begin() + nearest.size() / 2, nearest.end());
  const double radius = std::max(1.5, 0.4 * nearest[nearest.size() / 2]);
  const std::vector<double> all = BlobSignals(all_dots, blobs, radius, session.Entry(all_dots_key).exposure_s);
  const std::vector<double> lit = BlobSignals(fiducial, blobs, radius, session.Entry(keys.front()).exposure_s);
  std::vector<bool> on(blobs.size());
  for (size_t b = 0; b < blobs.size(); ++b) on[b] = all[b] > 0 && lit[b] > 0.5 * all[b];
  return on;
}

// A dot whose centroid lies this far from the fitted grid is not that dot (a speck, or two blobs
// merged); beyond a tenth of the dots so placed, the grid is not the displayed one.
constexpr double kOutlierResidualMm = 1.0;
constexpr double kMaxOutlierFraction = 0.1;
// Blob noise puts the dots' RMS residual at 0.01-0.05 mm on the simulated rigs; a fit ten times
// worse is no measurement of the dots.
constexpr double kMaxResidualRmsMm = 0.5;

MonitorCalibration CalibrateMonitor(const session::Session& session, const CameraModel& camera, const SamplePlane& plane) {
  const std::vector<std::string> keys = session.PlannedKeys(session::CaptureKind::kAllDots);
  if (keys.empty()) common::ThrowInvalidInput(session.folder().string(), "plans no all_dots/ capture (every dot lit, sample removed)");
  const NominalDots nominal = ReadNominalDots(session);
  const DisplayedGrid& grid = nominal.grid;
  const cv::Size size(camera.width, camera.height);
  const cv::Mat gray = GrayImage(session, keys.front(), size);
  const std::vector<Eigen::Vector2d> blobs = FindBlobs(gray);
  std::vector<Eigen::Vector2d> on_plane;
  for (const auto& b : blobs) on_plane.push_back(BackProject(b, camera, plane, -nominal.distance_m).head<2>());
  const std::vector<bool> lit = FiducialBlobs(session, keys.front(), gray, blobs, size);
  const std::vector<std::string> fiducial_keys = session.PlannedKeys(session::CaptureKind::kFiducials);
  const std::string decider = fiducial_keys.empty() ? (session.folder() / "session.json").string()
                                                    : ImageFile(session, fiducial_keys.front());
  if (!fiducial_keys.empty() && grid.fiducial.empty()) {
    common::ThrowFormatError((session.folder() / "session.json").string(),
                     "plans a fiducials/ capture but does not say which dots it lit (rig.dots.fiducials)");
  }
  const DotIdentification id = IdentifyDots(on_plane, lit, grid, nominal.orientation_deg, decider);
  std::vector<int> match = id.chosen.blob_of_dot;
  if (match.empty()) match.assign(grid.monitor_px.size(), -1);
  const auto monitor_point = [&](size_t q) {
    return cv::Point3d(grid.monitor_px[q].x() * grid.pixel_pitch_m, grid.monitor_px[q].y() * grid.pixel_pitch_m, 0.0);
  };
  MonitorCalibration monitor;
  Eigen::Matrix3d to_sample;
  model::Vec3 origin;
  int outliers = 0;
  // The monitor's pose from its dots, in the screen's own frame: u right, v down (seen from the
  // front), so its z axis u x v points into the screen, away from the sample. Dots far off the
  // fitted grid are dropped and the pose fitted again.
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<cv::Point3d> object;
    std::vector<cv::Point2d> image;
    for (size_t q = 0; q < match.size(); ++q) {
      if (match[q] < 0) continue;
      object.push_back(monitor_point(q));
      image.emplace_back(blobs[match[q]].x(), blobs[match[q]].y());
    }
    if (object.size() < std::max<size_t>(4, match.size() / 2)) {
      common::ThrowFormatError(ImageFile(session, keys.front()), "shows " + std::to_string(object.size()) + " of the " +
                                                             std::to_string(match.size()) + " displayed dots",
                       "check that the sample is removed, the room dark and the exposure right");
    }
    cv::Vec3d rvec, tvec;
    cv::solvePnP(object, image, camera.CameraMatrix(), camera.DistortionCoefficients(), rvec, tvec, false,
                 cv::SOLVEPNP_IPPE);
    cv::Mat r;
    cv::Rodrigues(rvec, r);
    Eigen::Matrix3d monitor_rotation;
    cv::cv2eigen(r, monitor_rotation);
    to_sample = plane.rotation.transpose() * monitor_rotation;
    origin = plane.rotation.transpose() * (model::Vec3(tvec[0], tvec[1], tvec[2]) - plane.translation);
    monitor.normal = -to_sample.col(2).normalized();
    if (!(monitor.normal.z() > 0)) {
      common::ThrowFormatError(ImageFile(session, keys.front()),
                       "fits a monitor whose pixel axes, seen from the sample, form a mirror image of a screen "
                       "(u x v toward the sample)",
                       "turn off the display's mirror or flip mode, or check rig.dots.positions_px");
    }
    if (pass == 1) break;
    // Drop the dots far off this grid, if any, and fit once more without them.
    outliers = 0;
    for (size_t q = 0; q < match.size(); ++q) {
      if (match[q] < 0) continue;
      const model::Vec3 position = origin + to_sample * model::Vec3(monitor_point(q).x, monitor_point(q).y, 0.0);
      if (DotResidualMm(blobs[match[q]], position, monitor.normal, camera, plane) > kOutlierResidualMm) {
        match[q] = -1;
        ++outliers;
      }
    }
    if (outliers > kMaxOutlierFraction * match.size()) {
      common::ThrowFormatError(ImageFile(session, keys.front()),
                       "shows " + std::to_string(outliers) + " of the " + std::to_string(match.size()) +
                           " dots more than 1 mm off any flat grid of the layout rig.dots.positions_px describes",
                       "check rig.dots.positions_px and rig.monitor.pixel_pitch_m against what the display showed");
    }
    if (outliers == 0) break;
  }
  monitor.distance_m = std::abs(monitor.normal.dot(origin)) / std::max(1e-9, std::abs(monitor.normal.z()));
  monitor.pixel_pitch_m = grid.pixel_pitch_m;
  monitor.dot_radius_m = nominal.radius_px * grid.pixel_pitch_m;
  // Checked by CalibrateSession: empty (not noted) or a known profile.
  // A nominal profile only: `svbtdf calibrate-emission` measures one (calib/emission_fit.h).
  monitor.emission.kind = session.rig().monitor.emission.empty() ? "isotropic" : session.rig().monitor.emission;
  // The screen's u axis in the sample plane, as measured by the pose.
  const model::Vec3 right = to_sample.col(0);
  monitor.orientation_deg = std::fmod(360.0 + std::atan2(right.y(), right.x()) * 180.0 / model::kPi, 360.0);
  monitor.identified_by = id.identified_by == "fiducials" ? fiducial_keys.front() : id.identified_by;
  monitor.fiducial_agreement = id.chosen.fiducial_agreement;
  monitor.fiducial_runner_up = id.runner_up_agreement;
  double sum = 0;
  int found = 0;
  for (size_t q = 0; q < match.size(); ++q) {
    DotPosition dot;
    dot.monitor_px = grid.monitor_px[q] - Eigen::Vector2d(0.5, 0.5);
    dot.position = origin + to_sample * model::Vec3(monitor_point(q).x, monitor_point(q).y, 0.0);
    dot.image_px = match[q] >= 0 ? blobs[match[q]] : Eigen::Vector2d(-1.0, -1.0);  // -1: not found
    if (match[q] >= 0) {
      dot.residual_mm = DotResidualMm(blobs[match[q]], dot.position, monitor.normal, camera, plane);
      sum += dot.residual_mm * dot.residual_mm;
      monitor.residual_max_mm = std::max(monitor.residual_max_mm, dot.residual_mm);
      ++found;
    } else {
      dot.residual_mm = -1.0;  // not found: its position comes from the fitted grid alone
    }
    monitor.dots.push_back(dot);
  }
  monitor.residual_rms_mm = std::sqrt(sum / found);
  if (monitor.residual_rms_mm > kMaxResidualRmsMm) {
    common::ThrowFormatError(ImageFile(session, keys.front()),
                     "shows dots " + std::to_string(monitor.residual_rms_mm) +
                         " mm RMS off the fitted grid, far above the blob noise",
                     "check rig.dots.positions_px, rig.monitor.pixel_pitch_m, and that the monitor is flat");
  }
  return monitor;
}

Radiometry RadiometryOf(const session::Session& session, int bits, const cv::Size& size) {
  Radiometry r;
  r.bit_depth = bits;
  r.saturation_dn = MaxDn(bits);  // clipped values sit at full scale
  const std::string response = session.rig().camera.response.empty() ? "linear" : session.rig().camera.response;
  if (response == "srgb") {
    // The sRGB transfer curve inverted, in digital-number units so that "linear" and "table"
    // agree at full scale.
    r.response = "table";
    constexpr int kEntries = 1024;
    for (int k = 0; k < kEntries; ++k) {
      const double v = static_cast<double>(k) / (kEntries - 1);
      const double linear = v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
      r.inverse_response.push_back(linear * MaxDn(bits));
    }
  } else if (response != "linear") {
    common::ThrowFormatError((session.folder() / "session.json").string(), "has camera response '" + response + "'",
                     "use 'linear' or 'srgb' (docs/calibration-format.md)");
  }
  // The black offset: the median of the first dark frame (dark current adds little to it).
  const std::vector<std::string> darks = session.PlannedKeys(session::CaptureKind::kDark);
  if (!darks.empty()) {
    const cv::Mat dark = GrayImage(session, darks.front(), size);
    std::vector<float> values(dark.begin<float>(), dark.end<float>());
    std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
    r.black_offset_dn = values[values.size() / 2];
  }
  return r;
}

// Where the session's images lie on the sensor (docs/session-format.md, rig.camera.sensor): the
// Zhang board views are whole-sensor images when the other captures are a window of it.
struct SensorWindow {
  cv::Size sensor;
  cv::Point offset;  // the window's top-left pixel on the sensor
};

SensorWindow WindowOnSensor(const session::SensorWindow& described, const cv::Size& window, const std::string& manifest) {
  if (described.whole_sensor()) return {window, {0, 0}};
  const SensorWindow w{{described.sensor_width, described.sensor_height}, {described.offset_x, described.offset_y}};
  if (w.offset.x < 0 || w.offset.y < 0 || w.offset.x + window.width > w.sensor.width ||
      w.offset.y + window.height > w.sensor.height) {
    common::ThrowFormatError(manifest, "has a " + std::to_string(window.width) + "x" + std::to_string(window.height) +
                                   " window at (" + std::to_string(w.offset.x) + ", " + std::to_string(w.offset.y) +
                                   ") that does not lie on its " + std::to_string(w.sensor.width) + "x" +
                                   std::to_string(w.sensor.height) + " sensor (rig.camera.sensor)");
  }
  return w;
}

// The whole sensor's intrinsics as the window's: the same lens, the principal point measured
// from the window's corner.
void MoveToWindow(const SensorWindow& w, const cv::Size& window, CameraModel* camera) {
  camera->cx -= w.offset.x;
  camera->cy -= w.offset.y;
  camera->width = window.width;
  camera->height = window.height;
}

}  // namespace

SessionCalibration CalibrateSession(const session::Session& session, const CalibrateSessionOptions& options) {
  const std::string manifest = (session.folder() / "session.json").string();
  const session::RigDescription& rig = session.rig();
  const int bits = rig.camera.bit_depth, width = rig.camera.width, height = rig.camera.height;
  const double sample_width = rig.sample.width_m, sample_height = rig.sample.height_m;
  if (bits <= 0 || width <= 0 || height <= 0 || rig.board.spec.empty() || !(sample_width > 0) || !(sample_height > 0)) {
    common::ThrowFormatError(manifest, "does not describe the rig",
                     "calibration needs rig.camera (width, height, bit_depth), rig.board.spec and rig.sample "
                     "(width_m, height_m)");
  }
  const std::string& emission = rig.monitor.emission;
  if (!emission.empty() && emission != "isotropic" && emission != "lambertian" && emission != "lcd") {
    common::ThrowFormatError(manifest, "has rig.monitor.emission '" + emission + "'",
                     "use isotropic, lambertian or lcd (docs/calibration-format.md)");
  }
  const BoardSpec board = BoardSpec::Parse(rig.board.spec, manifest + " rig.board.spec");
  const std::string& holder_text = rig.sample_plane_board.spec.empty() ? rig.board.spec : rig.sample_plane_board.spec;
  const BoardSpec holder_board = BoardSpec::Parse(holder_text, manifest + " rig.sample_plane_board.spec");
  const cv::Size size(width, height);
  const SensorWindow window = WindowOnSensor(rig.camera.sensor, size, manifest);
  SessionCalibration c;
  c.camera = CalibrateCameraFromBoards(session, board, window.sensor, bits, options);
  MoveToWindow(window, size, &c.camera.camera);
  c.sample_plane = SamplePlaneFromBoard(session, holder_board, c.camera.camera, bits);
  c.sample_plane.width_m = sample_width;
  c.sample_plane.height_m = sample_height;
  c.monitor = CalibrateMonitor(session, c.camera.camera, c.sample_plane);
  c.radiometry = RadiometryOf(session, bits, size);
  c.provenance = {{"session", std::filesystem::absolute(session.folder()).string()}, {"board", board.ToString()},
                  {"sample_plane_board", holder_board.ToString()}};
  if (window.sensor != size) {
    c.provenance["sensor"] = {{"width", window.sensor.width}, {"height", window.sensor.height},
                              {"window_offset", {window.offset.x, window.offset.y}}};
  }
  return c;
}

}  // namespace svbtdf::calib
