#include "svbtdf/calib/session_calibration.h"

#include <algorithm>
#include <cmath>

#include <opencv2/calib3d.hpp>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/json.h"
#include "svbtdf/common/error.h"

namespace svbtdf::calib {
namespace {

nlohmann::json ToJson(const model::Vec3& v) { return {v.x(), v.y(), v.z()}; }
nlohmann::json ToJson(const Eigen::Vector2d& v) { return {v.x(), v.y()}; }

model::Vec3 Vec3FromJson(const nlohmann::json& j) { return {j.at(0).get<double>(), j.at(1).get<double>(), j.at(2).get<double>()}; }
Eigen::Vector2d Vec2FromJson(const nlohmann::json& j) { return {j.at(0).get<double>(), j.at(1).get<double>()}; }

CalibrationReport CameraFromJson(const nlohmann::json& j, const std::string& source) {
  CalibrationReport report;
  CameraModel& c = report.camera;
  c.width = common::IntegerAt(j, "width", source);
  c.height = common::IntegerAt(j, "height", source);
  c.fx = j.at("fx").get<double>();
  c.fy = j.at("fy").get<double>();
  c.cx = j.at("cx").get<double>();
  c.cy = j.at("cy").get<double>();
  c.distortion = j.at("distortion").get<std::array<double, 5>>();
  report.rms_px = j.at("rms_px").get<double>();
  const std::string lens_model = j.value("lens_model", "full");
  if (lens_model == "centred") report.lens_model = lens_model;
  if (lens_model == "narrow") {
    report.narrow_lens_because = j.value("lens_model_because", "");
    if (report.narrow_lens_because.empty()) report.narrow_lens_because = "calibration.json says lens_model narrow";
  }
  if (j.contains("std")) {
    const nlohmann::json& s = j["std"];
    report.intrinsics_std = {s.at("fx").get<double>(), s.at("fy").get<double>(), s.at("cx").get<double>(),
                             s.at("cy").get<double>()};
    report.distortion_std = s.at("distortion").get<std::array<double, 5>>();
  }
  if (j.contains("projection_uncertainty_px")) {  // optional: files written before it lack it
    const nlohmann::json& u = j["projection_uncertainty_px"];
    report.projection_uncertainty.centre_px = u.at("centre").get<double>();
    report.projection_uncertainty.corners_px = u.at("corners").get<std::array<double, 4>>();
    report.projection_uncertainty.worst_px = u.at("worst").get<double>();
  }
  for (const nlohmann::json& v : j.value("views", nlohmann::json::array())) {
    ViewReport view;
    view.source = v.at("source").get<std::string>();
    view.used = v.at("used").get<bool>();
    view.rms_px = v.at("rms_px").get<double>();
    view.dropped_because = v.value("dropped_because", "");
    report.views.push_back(view);
  }
  return report;
}

void RequirePositiveFinite(double value, const std::string& source, const std::string& key) {
  if (!(value > 0.0) || !std::isfinite(value)) {
    common::ThrowFormatError(source, "has " + key + " = " + std::to_string(value) + "; it must be positive and finite");
  }
}

}  // namespace

nlohmann::json ToJson(const SessionCalibration& calibration) {
  nlohmann::json camera = ToJson(calibration.camera);
  const SamplePlane& plane = calibration.sample_plane;
  nlohmann::json rotation = nlohmann::json::array();
  for (int r = 0; r < 3; ++r) rotation.push_back({plane.rotation(r, 0), plane.rotation(r, 1), plane.rotation(r, 2)});
  const MonitorCalibration& m = calibration.monitor;
  nlohmann::json dots = nlohmann::json::array();
  for (const DotPosition& d : m.dots) {
    dots.push_back({{"position_m", ToJson(d.position)},
                    {"image_px", ToJson(d.image_px)},
                    {"monitor_px", ToJson(d.monitor_px)},
                    {"residual_mm", d.residual_mm}});
  }
  const Radiometry& r = calibration.radiometry;
  nlohmann::json monitor = {{"normal", ToJson(m.normal)},
                            {"distance_m", m.distance_m},
                            {"pixel_pitch_m", m.pixel_pitch_m},
                            {"dot_radius_m", m.dot_radius_m},
                            {"residual_rms_mm", m.residual_rms_mm},
                            {"residual_max_mm", m.residual_max_mm},
                            {"orientation_deg", m.orientation_deg},
                            {"identification",
                             {{"by", m.identified_by}, {"fiducial_agreement", m.fiducial_agreement},
                              {"fiducial_runner_up", m.fiducial_runner_up}}},
                            {"dots", dots}};
  PutEmissionProfile(m.emission, &monitor);
  return {
      {"format", "svbtdf-calibration"},
      {"version", calibration.version},
      {"camera", camera},
      {"sample_plane",
       {{"rotation", rotation},
        {"translation_m", ToJson(plane.translation)},
        {"camera_centre_m", ToJson(plane.CameraCentre())},
        {"rms_px", plane.rms_px},
        {"width_m", plane.width_m},
        {"height_m", plane.height_m}}},
      {"monitor", monitor},
      {"radiometry",
       {{"response", r.response},
        {"inverse_response", r.inverse_response},
        {"bit_depth", r.bit_depth},
        {"saturation_dn", r.saturation_dn},
        {"black_offset_dn", r.black_offset_dn}}},
      {"provenance", calibration.provenance},
  };
}

SessionCalibration SessionCalibrationFromJson(const nlohmann::json& json, const std::string& source) {
  SessionCalibration c;
  try {
    if (json.at("format") != "svbtdf-calibration") common::ThrowFormatError(source, "is not an svbtdf calibration");
    c.version = common::IntegerAt(json, "version", source);
    if (c.version != 1 && c.version != kCalibrationFormatVersion) {
      common::ThrowFormatError(source, "has calibration format version " + std::to_string(c.version) +
                                   "; this svbtdf reads versions 1 and " + std::to_string(kCalibrationFormatVersion),
                       "re-run 'svbtdf calibrate' on the session");
    }
    c.camera = CameraFromJson(json.at("camera"), source);
    const nlohmann::json& plane = json.at("sample_plane");
    for (int r = 0; r < 3; ++r) {
      for (int k = 0; k < 3; ++k) c.sample_plane.rotation(r, k) = plane.at("rotation").at(r).at(k).get<double>();
    }
    c.sample_plane.translation = Vec3FromJson(plane.at("translation_m"));
    c.sample_plane.rms_px = plane.at("rms_px").get<double>();
    c.sample_plane.width_m = plane.at("width_m").get<double>();
    c.sample_plane.height_m = plane.at("height_m").get<double>();
    const nlohmann::json& m = json.at("monitor");
    c.monitor.normal = Vec3FromJson(m.at("normal"));
    c.monitor.distance_m = m.at("distance_m").get<double>();
    c.monitor.pixel_pitch_m = m.at("pixel_pitch_m").get<double>();
    c.monitor.dot_radius_m = m.at("dot_radius_m").get<double>();
    c.monitor.emission = EmissionProfileFromJson(m, source);
    c.monitor.residual_rms_mm = m.value("residual_rms_mm", 0.0);
    c.monitor.residual_max_mm = m.value("residual_max_mm", 0.0);
    c.monitor.orientation_deg = m.value("orientation_deg", 0.0);
    if (m.contains("identification")) {
      const nlohmann::json& id = m.at("identification");
      c.monitor.identified_by = id.value("by", "");
      c.monitor.fiducial_agreement = id.value("fiducial_agreement", -1.0);
      c.monitor.fiducial_runner_up = id.value("fiducial_runner_up", -1.0);
    }
    for (const nlohmann::json& d : m.at("dots")) {
      DotPosition dot;
      dot.position = Vec3FromJson(d.at("position_m"));
      dot.image_px = Vec2FromJson(d.at("image_px"));
      dot.monitor_px = Vec2FromJson(d.at("monitor_px"));
      dot.residual_mm = d.value("residual_mm", 0.0);
      c.monitor.dots.push_back(dot);
    }
    const nlohmann::json& r = json.at("radiometry");
    c.radiometry.response = r.at("response").get<std::string>();
    c.radiometry.inverse_response = r.value("inverse_response", std::vector<double>{});
    c.radiometry.bit_depth = common::IntegerAt(r, "bit_depth", source);
    c.radiometry.saturation_dn = r.at("saturation_dn").get<double>();
    c.radiometry.black_offset_dn = r.value("black_offset_dn", 0.0);
    c.provenance = json.value("provenance", nlohmann::json::object());
    c.version = kCalibrationFormatVersion;  // a version 1 file is a version 2 file without a measured profile
  } catch (const nlohmann::json::exception& e) {
    common::ThrowFormatError(source, std::string("is malformed: ") + e.what(), "re-run 'svbtdf calibrate' on the session");
  }
  const CameraModel& cam = c.camera.camera;
  RequirePositiveFinite(cam.fx, source, "camera.fx");
  RequirePositiveFinite(cam.fy, source, "camera.fy");
  RequirePositiveFinite(cam.width, source, "camera.width");
  RequirePositiveFinite(cam.height, source, "camera.height");
  RequirePositiveFinite(c.monitor.distance_m, source, "monitor.distance_m");
  RequirePositiveFinite(c.monitor.dot_radius_m, source, "monitor.dot_radius_m");
  RequirePositiveFinite(c.sample_plane.width_m, source, "sample_plane.width_m");
  RequirePositiveFinite(c.sample_plane.height_m, source, "sample_plane.height_m");
  if (c.monitor.dots.empty()) common::ThrowFormatError(source, "lists no dots");
  if (c.radiometry.response != "linear" && c.radiometry.response != "table") {
    common::ThrowFormatError(source, "has an unknown radiometry.response '" + c.radiometry.response + "'");
  }
  if (c.sample_plane.CameraCentre().z() <= 0.0) {
    common::ThrowFormatError(source, "puts the camera behind the sample plane (sample_plane pose is wrong)");
  }
  return c;
}

SessionCalibration ReadSessionCalibration(const std::filesystem::path& path) {
  return SessionCalibrationFromJson(common::ReadJsonFile(path), path.string());
}

void WriteSessionCalibration(const std::filesystem::path& path, const SessionCalibration& calibration) {
  common::WriteTextAtomically(path, ToJson(calibration).dump(2) + "\n", /*overwrite=*/true);
}

std::vector<Eigen::Vector2d> ProjectToImage(const SessionCalibration& calibration, const std::vector<model::Vec3>& points) {
  if (points.empty()) return {};
  std::vector<cv::Point3d> object(points.size());
  for (size_t k = 0; k < points.size(); ++k) {
    const model::Vec3 c = calibration.sample_plane.ToCamera(points[k]);
    object[k] = {c.x(), c.y(), c.z()};
  }
  std::vector<cv::Point2d> image;
  // The points are already in the camera frame: identity pose.
  cv::projectPoints(object, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), calibration.camera.camera.CameraMatrix(),
                    calibration.camera.camera.DistortionCoefficients(), image);
  std::vector<Eigen::Vector2d> out(points.size());
  for (size_t k = 0; k < points.size(); ++k) out[k] = {image[k].x, image[k].y};
  return out;
}

}  // namespace svbtdf::calib
