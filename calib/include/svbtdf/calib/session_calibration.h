#pragma once
// The calibration of one capture session, SESSION/calibration.json (docs/calibration-format.md):
// everything `svbtdf process` needs to turn the session's images into BTDF samples.
//
// Frames: the sample frame of docs/model.md (the sample in z = 0 centred on the origin, z toward
// the camera, the monitor behind it at z < 0), metres. Camera: OpenCV pinhole with five-parameter
// Brown-Conrady distortion, x_cam = R x_sample + t.

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "svbtdf/calib/camera_calibration.h"
#include "svbtdf/calib/emission_profile.h"
#include "svbtdf/calib/radiometry.h"
#include "svbtdf/model/vec.h"

namespace svbtdf::calib {

// Version 2 adds the measured emission profile (monitor.emission "measured" with
// monitor.emission_profile); version 1 files are read as they are.
inline constexpr int kCalibrationFormatVersion = 2;

// Where the sample plane is: the pose of the sample frame in the camera frame, from the board
// lying in the sample holder (centred on the sample, its rows along the sample's x axis).
struct SamplePlane {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // R: sample frame -> camera frame
  model::Vec3 translation = model::Vec3::Zero();                          // t, metres
  double rms_px = 0.0;  // reprojection RMS of the holder board's corners
  double width_m = 0.08, height_m = 0.08;  // the sample's extent (nominal, from session.json)

  model::Vec3 CameraCentre() const { return -rotation.transpose() * translation; }  // V, sample frame
  model::Vec3 ToCamera(const model::Vec3& x_sample) const { return rotation * x_sample + translation; }
};

// One displayed dot.
struct DotPosition {
  model::Vec3 position = model::Vec3::Zero();             // p_q in the sample frame (on the monitor plane)
  Eigen::Vector2d image_px{0.0, 0.0};       // its centroid in the all-dots image
  Eigen::Vector2d monitor_px{0.0, 0.0};     // where it was displayed (monitor pixels)
  double residual_mm = 0.0;                 // |back-projected - fitted grid| on the monitor plane
};

// The monitor as measured: its plane and the dots on it.
struct MonitorCalibration {
  model::Vec3 normal = model::Vec3::UnitZ();  // unit, sample frame, pointing toward the sample
  double distance_m = 0.04;     // d: distance of the monitor plane behind the sample plane
  double pixel_pitch_m = 2.5e-4;
  double dot_radius_m = 5e-4;   // radius of a displayed dot (its lit area is pi r^2)
  EmissionProfile emission;     // the angular profile P(theta_e) (calib/emission_profile.h)
  double residual_rms_mm = 0.0, residual_max_mm = 0.0;  // dots vs the fitted grid
  // Which way the screen lies: the direction of its u axis (pixel x) in the sample plane,
  // counter-clockwise from +x seen from the camera side, degrees in [0, 360).
  double orientation_deg = 0.0;
  // What told which blob is which dot: the fiducial capture's key, or "declared orientation"
  // (rig.monitor.orientation_deg); the fraction of dots agreeing with the chosen orientation and
  // with the next best (-1: not measured).
  std::string identified_by;
  double fiducial_agreement = -1.0, fiducial_runner_up = -1.0;
  std::vector<DotPosition> dots;  // in plan order (q row-major over the grid)

  // The angular emission profile P(theta_e) relative to the normal direction.
  double Emission(double cos_theta) const { return emission(cos_theta); }
};

struct SessionCalibration {
  int version = kCalibrationFormatVersion;
  CalibrationReport camera;      // intrinsics, distortion, RMS and per-view errors
  SamplePlane sample_plane;
  MonitorCalibration monitor;
  Radiometry radiometry;
  nlohmann::json provenance = nlohmann::json::object();  // session, software, options
};

// calibration.json <-> SessionCalibration. The JSON has at least camera.fx, camera.fy, camera.cx,
// camera.cy, camera.distortion, camera.rms_px (the keys the simulator's truth/rig.json uses).
nlohmann::json ToJson(const SessionCalibration& calibration);
// Throws svbtdf::Error(kFormat) naming `source` for a missing key, a wrong version or a bad value.
SessionCalibration SessionCalibrationFromJson(const nlohmann::json& json, const std::string& source);

// Reads `path` (svbtdf::Error naming it on any problem) / writes it atomically (temp + rename).
SessionCalibration ReadSessionCalibration(const std::filesystem::path& path);
void WriteSessionCalibration(const std::filesystem::path& path, const SessionCalibration& calibration);

// Projects sample-frame points to distorted image pixels with the calibrated camera.
std::vector<Eigen::Vector2d> ProjectToImage(const SessionCalibration& calibration, const std::vector<model::Vec3>& points);

}  // namespace svbtdf::calib
