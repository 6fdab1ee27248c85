#pragma once
// Test and benchmark support: the calibration a perfect `svbtdf calibrate` would write for a
// session made by `svbtdf simulate`, built from its ground truth (DIR/truth/rig.json). It lets the
// processing and fitting be measured apart from the calibration's own errors.

#include <cmath>
#include <filesystem>

#include "svbtdf/calib/session_calibration.h"
#include "svbtdf/session/session.h"
#include "svbtdf/simulate/truth_io.h"

namespace svbtdf {

// `simulation` is the folder holding session/ and truth/.
inline calib::SessionCalibration CalibrationFromTruth(const std::filesystem::path& simulation) {
  const simulate::RigTruth truth = simulate::ReadRigTruth(simulation / "truth" / "rig.json");
  const session::Session session = session::Session::Open(simulation / "session");
  calib::SessionCalibration c;
  calib::CameraModel& camera = c.camera.camera;
  camera.width = truth.camera.width;
  camera.height = truth.camera.height;
  camera.fx = truth.camera.fx;
  camera.fy = truth.camera.fy;
  camera.cx = truth.camera.cx;
  camera.cy = truth.camera.cy;
  camera.distortion = truth.camera.distortion;
  c.sample_plane.rotation = truth.pose.rotation;
  c.sample_plane.translation = truth.pose.translation;
  c.sample_plane.width_m = truth.sample.width;
  c.sample_plane.height_m = truth.sample.height();
  c.monitor.normal = simulate::MonitorFrame::Of(truth.monitor).normal;  // the screen may be tilted
  // Which way it lies: its u axis's direction in the sample plane, counter-clockwise from +x.
  const model::Vec3 right = simulate::MonitorFrame::Of(truth.monitor).right;
  c.monitor.orientation_deg = std::fmod(std::atan2(right.y(), right.x()) * 180.0 / model::kPi + 360.0, 360.0);
  c.monitor.distance_m = truth.monitor.distance;
  c.monitor.pixel_pitch_m = truth.monitor.pixel_pitch;
  c.monitor.dot_radius_m = truth.dots.front().radius;
  c.monitor.emission.kind = truth.monitor.emission.kind;
  c.monitor.emission.exponent = truth.monitor.emission.exponent;
  for (const simulate::Dot& dot : truth.dots) {
    calib::DotPosition p;
    p.position = dot.position;
    p.monitor_px = {dot.monitor_x, dot.monitor_y};
    c.monitor.dots.push_back(p);
  }
  const int bits = session.rig().camera.bit_depth;
  c.radiometry.bit_depth = bits;
  c.radiometry.saturation_dn = std::ldexp(1.0, bits) - 1.0;  // the simulator clips at full scale
  return c;
}


}  // namespace svbtdf
