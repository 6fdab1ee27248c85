#include "svbtdf/simulate/rig.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "svbtdf/common/error.h"

namespace svbtdf::simulate {
namespace {

std::string Fmt(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.6g", value);
  return buffer;
}

void RequirePositive(double value, const std::string& name) {
  if (!(value > 0.0) || !std::isfinite(value)) {
    common::ThrowInvalidInput(name, "must be a positive finite number, got " + Fmt(value));
  }
}

}  // namespace

CameraPose CameraPose::LookAt(const model::Vec3& eye, const model::Vec3& target, const model::Vec3& up_hint) {
  const model::Vec3 forward = (target - eye).normalized();
  const model::Vec3 right = forward.cross(up_hint);
  if (right.norm() < 1e-9) {
    common::ThrowInvalidInput("camera pose", "the up hint is parallel to the viewing direction");
  }
  const model::Vec3 x = right.normalized();
  const model::Vec3 y = forward.cross(x);  // image down
  CameraPose pose;
  pose.rotation.row(0) = x;
  pose.rotation.row(1) = y;
  pose.rotation.row(2) = forward;
  pose.translation = -pose.rotation * eye;
  return pose;
}

PinholeCamera::PinholeCamera(CameraIntrinsics intrinsics, CameraPose pose)
    : intrinsics_(intrinsics), pose_(pose), centre_(pose.Centre()) {}

model::Vec2 PinholeCamera::Distort(const model::Vec2& p) const {
  const auto& d = intrinsics_.distortion;
  const double x = p.x(), y = p.y();
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (d[0] + r2 * (d[1] + r2 * d[4]));
  return {x * radial + 2.0 * d[2] * x * y + d[3] * (r2 + 2.0 * x * x),
          y * radial + d[2] * (r2 + 2.0 * y * y) + 2.0 * d[3] * x * y};
}

std::optional<model::Vec2> PinholeCamera::Undistort(const model::Vec2& distorted, const model::Vec2* start) const {
  const auto& d = intrinsics_.distortion;
  model::Vec2 p = start ? *start : distorted;
  for (int iteration = 0; iteration < 50; ++iteration) {
    const double x = p.x(), y = p.y();
    const double r2 = x * x + y * y;
    const double radial = 1.0 + r2 * (d[0] + r2 * (d[1] + r2 * d[4]));
    const double dradial = d[0] + r2 * (2.0 * d[1] + 3.0 * r2 * d[4]);  // d radial / d r2
    Eigen::Matrix2d jacobian;
    jacobian(0, 0) = radial + 2.0 * x * x * dradial + 2.0 * d[2] * y + 6.0 * d[3] * x;
    jacobian(0, 1) = 2.0 * x * y * dradial + 2.0 * d[2] * x + 2.0 * d[3] * y;
    jacobian(1, 0) = 2.0 * x * y * dradial + 2.0 * d[2] * x + 2.0 * d[3] * y;
    jacobian(1, 1) = radial + 2.0 * y * y * dradial + 6.0 * d[2] * y + 2.0 * d[3] * x;
    const model::Vec2 residual = Distort(p) - distorted;
    if (residual.norm() < 1e-14) return p;
    const double det = jacobian.determinant();
    if (!(std::abs(det) > 1e-12)) return std::nullopt;
    p -= jacobian.inverse() * residual;
    if (!p.allFinite()) return std::nullopt;
  }
  if ((Distort(p) - distorted).norm() < 1e-10) return p;
  return std::nullopt;
}

std::optional<model::Vec2> PinholeCamera::Project(const model::Vec3& world) const {
  const model::Vec3 c = pose_.rotation * world + pose_.translation;
  if (!(c.z() > 0.0)) return std::nullopt;
  const model::Vec2 q = Distort(model::Vec2(c.x() / c.z(), c.y() / c.z()));
  return model::Vec2(intrinsics_.fx * q.x() + intrinsics_.cx, intrinsics_.fy * q.y() + intrinsics_.cy);
}

std::optional<model::Vec2> PinholeCamera::ImagePoint(const model::Vec2& pixel, const model::Vec2* start) const {
  const model::Vec2 distorted((pixel.x() - intrinsics_.cx) / intrinsics_.fx,
                              (pixel.y() - intrinsics_.cy) / intrinsics_.fy);
  return Undistort(distorted, start);
}

model::Vec3 PinholeCamera::RayThrough(const model::Vec2& p) const {
  return (pose_.rotation.transpose() * model::Vec3(p.x(), p.y(), 1.0)).normalized();
}

std::optional<model::Vec3> PinholeCamera::PixelRay(const model::Vec2& pixel) const {
  const std::optional<model::Vec2> p = ImagePoint(pixel);
  if (!p) return std::nullopt;
  return RayThrough(*p);
}

double EmissionProfile::operator()(double cos_theta_e) const {
  const double c = std::clamp(cos_theta_e, 0.0, 1.0);
  if (kind == "isotropic") return c > 0.0 ? 1.0 : 0.0;
  if (kind == "lambertian") return c;
  return std::pow(c, exponent);  // lcd
}

EmissionProfile EmissionProfile::Parse(const std::string& spec, const std::string& option) {
  EmissionProfile profile;
  if (spec == "isotropic" || spec == "lambertian") {
    profile.kind = spec;
    return profile;
  }
  char* end = nullptr;
  const double n = spec.rfind("lcd:", 0) == 0 ? std::strtod(spec.c_str() + 4, &end) : 0.0;
  if (end == nullptr || *end != '\0' || end == spec.c_str() + 4 || !(n > 0.0 && n <= 20.0)) {
    common::ThrowInvalidInput(option, "must be isotropic, lambertian or lcd:N with 0 < N <= 20 (P = cos^N), got '" +
                                          spec + "'");
  }
  profile.kind = "lcd";
  profile.exponent = n;
  return profile;
}

model::Vec3 Polarisation::FieldDirection(const MonitorFrame& frame) const {
  const double a = angle_deg * model::kPi / 180.0;
  return (std::cos(a) * frame.right - std::sin(a) * frame.down).normalized();
}

Polarisation Polarisation::Parse(const std::string& spec, const std::string& option) {
  Polarisation polarisation;
  if (spec == "none") return polarisation;
  char* end = nullptr;
  const double angle = spec.rfind("linear:", 0) == 0 ? std::strtod(spec.c_str() + 7, &end) : 0.0;
  if (end == nullptr || *end != '\0' || end == spec.c_str() + 7 || !std::isfinite(angle)) {
    common::ThrowInvalidInput(option, "must be none or linear:DEG (the field's angle from the screen's pixel x axis "
                                      "toward its top, degrees), got '" + spec + "'");
  }
  polarisation.kind = "linear";
  polarisation.angle_deg = angle;
  return polarisation;
}

std::string Polarisation::ToString() const {
  if (!linear()) return "none";
  char text[64];
  std::snprintf(text, sizeof text, "linear:%g", angle_deg);
  return text;
}

double MonitorConfig::Luminance(double level) const {
  return black_level + (1.0 - black_level) * std::pow(std::clamp(level, 0.0, 1.0), gamma);
}

double NominalOrientationDeg(const MonitorConfig& monitor) {
  const double quarter_turns = std::round(monitor.orientation_deg / 90.0);
  return std::fmod(std::fmod(90.0 * quarter_turns, 360.0) + 360.0, 360.0);
}

MonitorFrame MonitorFrame::Of(const MonitorConfig& m) {
  const double phi = m.orientation_deg * model::kPi / 180.0, tau = m.tilt_deg * model::kPi / 180.0;
  // Orientation 0 seen from the sample (from +z): u along +x, v along -y; then turned by phi
  // about z and tilted by tau about x.
  const Eigen::AngleAxisd turn(phi, model::Vec3::UnitZ()), tilt(tau, model::Vec3::UnitX());
  MonitorFrame f;
  f.right = tilt * (turn * model::Vec3::UnitX());
  f.down = tilt * (turn * -model::Vec3::UnitY());
  f.normal = tilt * model::Vec3::UnitZ();
  if (m.mirrored) f.down = -f.down;
  f.pixel_pitch = m.pixel_pitch;
  f.width_px = m.width / m.pixel_pitch;
  f.height_px = m.height / m.pixel_pitch;
  const model::Vec3 centre(m.centre.x(), m.centre.y(), -m.distance);
  f.origin = centre - 0.5 * (m.width * f.right + m.height * f.down);
  return f;
}

model::Vec2 MonitorFrame::PixelCoordinates(const model::Vec3& point) const {
  const model::Vec3 d = point - origin;
  return model::Vec2(d.dot(right), d.dot(down)) / pixel_pitch;
}

std::optional<model::Vec3> MonitorFrame::Intersect(const model::Vec3& from, const model::Vec3& direction) const {
  const double along = normal.dot(direction);
  if (std::abs(along) < 1e-12) return std::nullopt;
  const double t = normal.dot(origin - from) / along;
  if (!(t > 0.0)) return std::nullopt;
  return from + t * direction;
}

CameraPose RigConfig::PaperPose(double distance, double theta) {
  const model::Vec3 eye(0.0, -distance * std::sin(theta), distance * std::cos(theta));
  return CameraPose::LookAt(eye, model::Vec3::Zero(), model::Vec3::UnitZ());
}

std::string BoardConfig::Spec() const {
  return "chessboard:" + std::to_string(inner_cols) + "x" + std::to_string(inner_rows) + ":" + Fmt(square * 1000.0);
}

namespace {

CameraIntrinsics WholeSensor(const CameraIntrinsics& window_intrinsics, const SensorWindow& window) {
  if (window.whole_sensor()) return window_intrinsics;
  CameraIntrinsics sensor = window_intrinsics;
  sensor.width = window.sensor_width;
  sensor.height = window.sensor_height;
  sensor.cx += window.offset_x;
  sensor.cy += window.offset_y;
  return sensor;
}

}  // namespace

Rig::Rig(RigConfig config)
    : config_(std::move(config)),
      camera_(config_.intrinsics, config_.pose),
      sensor_camera_(WholeSensor(config_.intrinsics, config_.window), config_.pose),
      monitor_frame_(MonitorFrame::Of(config_.monitor)) {
  Validate();
  LayOutDots();
}

double Rig::CameraTheta() const {
  const model::Vec3 c = camera_.Centre();
  return std::atan2(c.head<2>().norm(), c.z());
}

void Rig::Validate() const {
  const CameraIntrinsics& k = config_.intrinsics;
  if (k.width < 8 || k.height < 8) {
    common::ThrowInvalidInput("camera.width/height", "the image must be at least 8 x 8 pixels");
  }
  RequirePositive(k.fx, "camera.fx");
  RequirePositive(k.fy, "camera.fy");
  for (double v : k.distortion) {
    if (!std::isfinite(v)) common::ThrowInvalidInput("camera.distortion", "must be finite");
  }
  if (!config_.pose.rotation.allFinite() || !config_.pose.translation.allFinite() ||
      std::abs(config_.pose.rotation.determinant() - 1.0) > 1e-6) {
    common::ThrowInvalidInput("camera pose", "the rotation must be a proper rotation matrix");
  }
  const model::Vec3 centre = camera_.Centre();
  if (!(centre.z() > 0.0)) {
    common::ThrowInvalidInput("camera pose", "the camera is at z = " + Fmt(centre.z()) +
                      " m, on or below the sample plane",
                      "the camera must look down at the sample from z > 0 (the monitor is below)");
  }
  const SampleConfig& s = config_.sample;
  RequirePositive(s.width, "sample.width");
  if (s.texels_x < 1 || s.texels_y < 1) common::ThrowInvalidInput("sample.texels", "must be >= 1");
  // Every corner of the sample must project inside the image (with a half-pixel margin).
  for (double sx : {-0.5, 0.5}) {
    for (double sy : {-0.5, 0.5}) {
      const model::Vec3 corner(sx * s.width, sy * s.height(), 0.0);
      const std::optional<model::Vec2> px = camera_.Project(corner);
      if (!px || px->x() < 0.0 || px->y() < 0.0 || px->x() > k.width - 1.0 ||
          px->y() > k.height - 1.0) {
        common::ThrowInvalidInput("camera", "the sample corner (" + Fmt(corner.x()) + ", " +
                          Fmt(corner.y()) + ") m is not in view",
                          "move the camera back, lower fx/fy or enlarge the image");
      }
      const std::optional<model::Vec3> ray = camera_.PixelRay(*px);
      if (!ray || ((*ray) - (corner - centre).normalized()).norm() > 1e-6) {
        common::ThrowInvalidInput("camera.distortion", "the lens distortion is not invertible over the "
                          "sample's image", "use smaller distortion coefficients");
      }
    }
  }
  const MonitorConfig& m = config_.monitor;
  if (!(m.distance > 0.0) || !std::isfinite(m.distance)) {
    common::ThrowInvalidInput("monitor.distance", "the monitor must lie behind the sample (d > 0), got d = " +
                      Fmt(m.distance) + " m", "the monitor plane is z = -d, on the far side from the camera");
  }
  if (!std::isfinite(m.orientation_deg) || !(std::abs(m.tilt_deg) < 30.0)) {
    common::ThrowInvalidInput("monitor.orientation/tilt", "the orientation must be finite and the tilt within 30 degrees",
                      "the screen must face the sample");
  }
  RequirePositive(m.width, "monitor.width");
  RequirePositive(m.height, "monitor.height");
  RequirePositive(m.pixel_pitch, "monitor.pixel_pitch");
  RequirePositive(m.gamma, "monitor.gamma");
  RequirePositive(m.white_exitance, "monitor.white_exitance");
  if (!(m.black_level >= 0.0 && m.black_level < 1.0)) {
    common::ThrowInvalidInput("monitor.black_level", "must lie in [0, 1)");
  }
  const std::string& kind = m.emission.kind;
  if (kind != "isotropic" && kind != "lambertian" && kind != "lcd") {
    common::ThrowInvalidInput("monitor.emission", "unknown profile '" + kind + "'",
                      "use isotropic, lambertian or lcd");
  }
  if (kind == "lcd") RequirePositive(m.emission.exponent, "monitor.emission.exponent");
  if ((m.polarisation.kind != "none" && m.polarisation.kind != "linear") || !std::isfinite(m.polarisation.angle_deg)) {
    common::ThrowInvalidInput("monitor.polarisation", "unknown polarisation '" + m.polarisation.kind + "'",
                              "use none or linear with a finite angle");
  }
  const DotGridConfig& g = config_.dots;
  if (g.cols < 1 || g.rows < 1) common::ThrowInvalidInput("dots", "the grid needs at least 1 x 1 dots");
  RequirePositive(g.span_scale, "dots.span_scale");
  RequirePositive(g.radius_px, "dots.radius_px");
  if (!(g.level > 0.0 && g.level <= 1.0)) common::ThrowInvalidInput("dots.level", "must lie in (0, 1]");
  const SensorConfig& sensor = config_.sensor;
  if (sensor.exposures_s.empty()) common::ThrowInvalidInput("sensor.exposures", "at least one exposure");
  for (double t : sensor.exposures_s) RequirePositive(t, "sensor.exposures");
  RequirePositive(sensor.sensitivity, "sensor.sensitivity");
  RequirePositive(sensor.full_well, "sensor.full_well");
  if (!(sensor.read_noise >= 0.0)) common::ThrowInvalidInput("sensor.read_noise", "must be >= 0");
  if (!(sensor.dark_current >= 0.0)) common::ThrowInvalidInput("sensor.dark_current", "must be >= 0");
  if (sensor.bit_depth < 8 || sensor.bit_depth > 16) {
    common::ThrowInvalidInput("sensor.bit_depth", "must lie in [8, 16]");
  }
  if (sensor.response != "linear" && sensor.response != "srgb") {
    common::ThrowInvalidInput("sensor.response", "unknown response '" + sensor.response + "'",
                      "use linear or srgb");
  }
  if (!(sensor.vignetting >= 0.0 && sensor.vignetting < 1.0)) {
    common::ThrowInvalidInput("sensor.vignetting", "must lie in [0, 1)");
  }
  if (!(sensor.black_offset >= 0.0 && sensor.black_offset < 0.5)) {
    common::ThrowInvalidInput("sensor.black_offset", "must lie in [0, 0.5)");
  }
  if (config_.pixel_samples < 1 || config_.board_samples < 1) {
    common::ThrowInvalidInput("pixel_samples", "supersampling must be >= 1");
  }
  for (const auto& [b, name] : {std::pair{&config_.board, "board"}, std::pair{&config_.holder_board, "holder_board"}}) {
    if (b->inner_cols < 3 || b->inner_rows < 3) common::ThrowInvalidInput(name, "needs >= 3 x 3 inner corners");
    RequirePositive(b->square, std::string(name) + ".square");
  }
  if (config_.board.views < 3) common::ThrowInvalidInput("board.views", "Zhang calibration needs at least 3 views");
  const SensorWindow& w = config_.window;
  if (!w.whole_sensor() && (w.offset_x < 0 || w.offset_y < 0 || w.offset_x + k.width > w.sensor_width ||
                            w.offset_y + k.height > w.sensor_height)) {
    common::ThrowInvalidInput("window", "the " + std::to_string(k.width) + " x " + std::to_string(k.height) + " image at (" +
                                    std::to_string(w.offset_x) + ", " + std::to_string(w.offset_y) +
                                    ") does not lie on the " + std::to_string(w.sensor_width) + " x " +
                                    std::to_string(w.sensor_height) + " sensor");
  }
}

void Rig::LayOutDots() {
  const SampleConfig& s = config_.sample;
  const MonitorConfig& m = config_.monitor;
  const DotGridConfig& g = config_.dots;
  const MonitorFrame& frame = monitor_frame_;
  const model::Vec3 camera = camera_.Centre();
  // Away from the camera along its azimuth (the camera sits above some point of the plane).
  model::Vec2 away = -camera.head<2>();
  away = away.norm() > 1e-12 ? away.normalized() : model::Vec2::Zero();
  const double shift = g.shift >= 0.0 ? g.shift : m.distance * std::cos(CameraTheta());
  const model::Vec2 grid_centre = shift * away;
  const model::Vec2 centre_px = frame.PixelCoordinates(model::Vec3(grid_centre.x(), grid_centre.y(), -m.distance));
  // The grid covers span_scale times the sample's extent along each of the screen's axes.
  const auto extent = [&](const model::Vec3& axis) { return std::abs(axis.x()) * s.width + std::abs(axis.y()) * s.height(); };
  const model::Vec2 span_px = g.span_scale * model::Vec2(extent(frame.right), extent(frame.down)) / m.pixel_pitch;
  const bool planned = !g.positions_px.empty();
  if (planned && g.positions_px.size() != static_cast<size_t>(g.cols) * g.rows) {
    common::ThrowInvalidInput("dots.positions_px", "must list cols x rows positions");
  }
  dots_.clear();
  dots_.reserve(static_cast<size_t>(g.cols) * g.rows);
  for (int row = 0; row < g.rows; ++row) {
    for (int col = 0; col < g.cols; ++col) {
      // Column along u, row down the screen along v; a 1 x N grid sits on the centre line.
      const double fu = g.cols > 1 ? static_cast<double>(col) / (g.cols - 1) - 0.5 : 0.0;
      const double fv = g.rows > 1 ? static_cast<double>(row) / (g.rows - 1) - 0.5 : 0.0;
      const model::Vec2 in_monitor =
          planned ? model::Vec2(g.positions_px[row * g.cols + col].first, g.positions_px[row * g.cols + col].second)
                  : model::Vec2(centre_px + model::Vec2(fu * span_px.x(), fv * span_px.y()));
      if (in_monitor.x() - g.radius_px < 0.0 || in_monitor.y() - g.radius_px < 0.0 ||
          in_monitor.x() + g.radius_px > frame.width_px || in_monitor.y() + g.radius_px > frame.height_px) {
        const model::Vec3 nominal = frame.PointAt(in_monitor);
        common::ThrowInvalidInput("monitor", "dot (" + std::to_string(col) + ", " + std::to_string(row) +
                          ") at (" + Fmt(nominal.x()) + ", " + Fmt(nominal.y()) +
                          ") m is off the monitor's active area",
                          "use a larger monitor, move its centre or shrink dots.span_scale");
      }
      // A laid-out grid's dots are drawn centred on a monitor pixel; a plan's where it says.
      Dot dot = planned ? DotAt(in_monitor.x(), in_monitor.y(), g.radius_px, m.Luminance(g.level))
                        : DotAt(std::floor(in_monitor.x()), std::floor(in_monitor.y()), g.radius_px, m.Luminance(g.level));
      dot.col = col;
      dot.row = row;
      // The all-dots image (sample removed) must show every dot to locate it.
      const std::optional<model::Vec2> px = camera_.Project(dot.position);
      const CameraIntrinsics& k = config_.intrinsics;
      if (!px || px->x() < 2.0 || px->y() < 2.0 || px->x() > k.width - 3.0 ||
          px->y() > k.height - 3.0) {
        common::ThrowInvalidInput("dots", "dot (" + std::to_string(col) + ", " + std::to_string(row) +
                          ") at (" + Fmt(dot.position.x()) + ", " + Fmt(dot.position.y()) +
                          ") m is outside the camera's view of the monitor",
                          "shrink dots.span_scale, or widen the view (image size, fx/fy)");
      }
      dots_.push_back(dot);
    }
  }
}

Dot Rig::DotAt(double x_px, double y_px, double radius_px, double luminance) const {
  const MonitorConfig& m = config_.monitor;
  Dot dot;
  dot.col = dot.row = -1;
  dot.monitor_x = static_cast<int>(std::floor(x_px));
  dot.monitor_y = static_cast<int>(std::floor(y_px));
  dot.drawn_x = x_px;
  dot.drawn_y = y_px;
  dot.position = monitor_frame_.PointAt(model::Vec2(x_px + 0.5, y_px + 0.5));
  dot.radius = radius_px * m.pixel_pitch;
  dot.intensity = m.white_exitance * luminance * model::kPi * dot.radius * dot.radius;
  return dot;
}

double Rig::DotIntensityToward(const Dot& dot, const model::Vec3& x) const {
  return dot.intensity * config_.monitor.emission(monitor_frame_.CosEmission(dot.position, x));
}

std::optional<model::Vec3> Rig::SampleHit(const model::Vec2& pixel) const {
  const std::optional<model::Vec3> ray = camera_.PixelRay(pixel);
  if (!ray || !(ray->z() < 0.0)) return std::nullopt;
  const model::Vec3 c = camera_.Centre();
  const model::Vec3 x = c + (-c.z() / ray->z()) * (*ray);
  if (!TexelAt(x)) return std::nullopt;
  return model::Vec3(x.x(), x.y(), 0.0);
}

std::optional<std::array<int, 2>> Rig::TexelAt(const model::Vec3& x) const {
  const SampleConfig& s = config_.sample;
  const double u = (x.x() + 0.5 * s.width) / s.texel_pitch();
  const double v = (0.5 * s.height() - x.y()) / s.texel_pitch();
  if (!(u >= 0.0 && v >= 0.0 && u < s.texels_x && v < s.texels_y)) return std::nullopt;
  return std::array<int, 2>{static_cast<int>(u), static_cast<int>(v)};
}

model::Vec3 Rig::TexelCentre(int col, int row) const { return config_.sample.TexelCentre(col, row); }

}  // namespace svbtdf::simulate
