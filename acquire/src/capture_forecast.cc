#include "svbtdf/acquire/capture_forecast.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <sstream>

#include "svbtdf/acquire/capture_session.h"
#include "svbtdf/common/error.h"
#include "svbtdf/model/dual_microfacet.h"
#include "svbtdf/model/ggx.h"

namespace svbtdf::acquire {
namespace {

constexpr double kDegree = model::kPi / 180.0;

double AngleDeg(const model::Vec3& a, const model::Vec3& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) / kDegree;
}

CaptureDuration Duration(const std::vector<PlannedCapture>& captures, const CapturePlan& plan, double frame_time_s,
                         int control_delay_frames) {
  CaptureDuration d;
  std::optional<Pattern> shown;
  std::optional<double> exposure;
  for (const PlannedCapture& capture : captures) {
    if (!shown || !SamePattern(*shown, capture.pattern)) {  // as the capture loop decides
      shown = capture.pattern;
      d.settling_s += plan.settle_s;
      ++d.patterns;
    }
    const double frame = std::max(capture.exposure_s, frame_time_s);
    if (exposure != capture.exposure_s) {
      exposure = capture.exposure_s;
      d.control_s += control_delay_frames * frame;
      ++d.exposure_changes;
    }
    d.exposing_s += frame;
  }
  return d;
}

// Dot q of the plan as a point of the sample frame.
std::vector<model::Vec3> DotPositions(const CapturePlan& plan, const simulate::Rig& rig) {
  const simulate::MonitorFrame& frame = rig.monitor_frame();
  std::vector<model::Vec3> positions;
  for (size_t q = 0; q < plan.dots_px.size(); ++q) {
    const auto [x, y] = plan.dots_px[q];
    const model::Vec2 uv(x + 0.5, y + 0.5);
    if (!frame.InActiveArea(uv)) {
      common::ThrowInvalidInput("plan", "dot " + std::to_string(q) + " at (" + std::to_string(x) + ", " + std::to_string(y) +
                                            ") px lies off the rig's monitor (" + std::to_string(int(frame.width_px)) +
                                            " x " + std::to_string(int(frame.height_px)) + " px)",
                                "the plan and the rig must describe the same monitor");
    }
    positions.push_back(frame.PointAt(uv));
  }
  return positions;
}

DotCoverage CoverageAt(const std::string& where, const model::Vec3& x, const CapturePlan& plan,
                       const std::vector<model::Vec3>& dots, const simulate::Rig& rig) {
  DotCoverage c;
  c.where = where;
  const model::Vec3 o = (rig.camera().Centre() - x).normalized();
  const model::Vec3 through = -o;  // the light a smooth sheet passes straight to the camera
  c.min_incidence_deg = 180.0;
  size_t nearest = 0;
  double nearest_deg = std::numeric_limits<double>::infinity();
  for (size_t q = 0; q < dots.size(); ++q) {
    const model::Vec3 i = (dots[q] - x).normalized();
    const double incidence = AngleDeg(i, -model::Vec3::UnitZ());
    c.min_incidence_deg = std::min(c.min_incidence_deg, incidence);
    c.max_incidence_deg = std::max(c.max_incidence_deg, incidence);
    const double off = AngleDeg(i, through);
    c.reach_deg = std::max(c.reach_deg, off);
    if (off < nearest_deg) nearest_deg = off, nearest = q;
  }
  c.straight_through_to_nearest_dot_deg = nearest_deg;
  // Inside the grid: the straight-through point on the screen lies within the dots' bounding box
  // in monitor pixels.
  if (const std::optional<model::Vec3> hit = rig.monitor_frame().Intersect(x, through)) {
    const model::Vec2 uv = rig.monitor_frame().PixelCoordinates(*hit);
    double u0 = 1e300, u1 = -1e300, v0 = 1e300, v1 = -1e300;
    for (const auto& [u, v] : plan.dots_px) {
      u0 = std::min(u0, u + 0.5), u1 = std::max(u1, u + 0.5), v0 = std::min(v0, v + 0.5), v1 = std::max(v1, v + 0.5);
    }
    c.straight_through_in_grid = uv.x() >= u0 && uv.x() <= u1 && uv.y() >= v0 && uv.y() <= v1;
  }
  // The spacing to the nearest dot's grid neighbours (right and below, or left and above).
  const int cols = plan.dot_cols, rows = plan.dot_rows;
  const int col = static_cast<int>(nearest) % cols, row = static_cast<int>(nearest) / cols;
  const model::Vec3 i = (dots[nearest] - x).normalized();
  std::vector<double> steps;
  if (cols > 1) steps.push_back(AngleDeg(i, (dots[row * cols + (col + 1 < cols ? col + 1 : col - 1)] - x).normalized()));
  if (rows > 1) steps.push_back(AngleDeg(i, (dots[(row + 1 < rows ? row + 1 : row - 1) * cols + col] - x).normalized()));
  for (double s : steps) c.spacing_deg += s / steps.size();
  const double radius_m = plan.dot_radius_px * rig.config().monitor.pixel_pitch;
  c.dot_radius_deg = std::atan2(radius_m, (dots[nearest] - x).norm()) / kDegree;
  return c;
}

// The dual-microfacet model's transmission of a GGX lobe toward the camera from `x`, scanned over
// the incident direction through the straight-through one in two perpendicular planes: the mean
// full width at half maximum.
double LobeWidthDeg(double roughness, double eta, const model::Vec3& x, const simulate::Rig& rig) {
  const model::GgxNdf ndf(roughness);
  const model::DualMicrofacetModel slab(eta);
  const model::Vec3 o = (rig.camera().Centre() - x).normalized();
  const model::Vec3 through = -o;
  const model::Vec3 across = through.cross(model::Vec3::UnitX()).norm() > 1e-6
                                 ? through.cross(model::Vec3::UnitX()).normalized()
                                 : through.cross(model::Vec3::UnitY()).normalized();
  const model::Vec3 along = across.cross(through).normalized();
  constexpr double kStepDeg = 0.01, kMaxDeg = 80.0;
  double width = 0.0;
  for (const model::Vec3& axis : {across, along}) {
    const auto rho = [&](double deg) {
      const double t = deg * kDegree;
      const model::Vec3 i = (std::cos(t) * through + std::sin(t) * axis).normalized();
      return i.z() < -1e-6 ? slab.Rho(ndf, 0.5, i, o) : 0.0;
    };
    double peak = 0.0, peak_deg = 0.0;
    for (double deg = -kMaxDeg; deg <= kMaxDeg; deg += kStepDeg) {
      const double value = rho(deg);
      if (value > peak) peak = value, peak_deg = deg;
    }
    double lo = peak_deg, hi = peak_deg;
    while (hi < kMaxDeg && rho(hi) >= peak / 2) hi += kStepDeg;
    while (lo > -kMaxDeg && rho(lo) >= peak / 2) lo -= kStepDeg;
    width += (hi - lo) / 2.0;
  }
  return width;
}

std::string Clock(double seconds) {
  char buffer[48];
  const long s = std::lround(seconds);
  if (s >= 3600) {
    std::snprintf(buffer, sizeof buffer, "%ld h %02ld min", s / 3600, (s % 3600) / 60);
  } else if (s >= 60) {
    std::snprintf(buffer, sizeof buffer, "%ld min %02ld s", s / 60, s % 60);
  } else {
    std::snprintf(buffer, sizeof buffer, "%.1f s", seconds);
  }
  return buffer;
}

}  // namespace

CapturePlan ScaleExposures(CapturePlan plan, double shortest_s, double* factor) {
  const double k = shortest_s / *std::min_element(plan.exposures_s.begin(), plan.exposures_s.end());
  for (double& e : plan.exposures_s) e *= k;
  plan.board_exposure_s *= k;
  plan.all_dots_exposure_s *= k;
  plan.flat_white_exposure_s *= k;
  if (factor) *factor = k;
  return plan;
}

CaptureForecast ForecastCapture(const CapturePlan& plan, const simulate::RigFile& rig_file, const std::string& rig_name,
                                const std::vector<double>& roughnesses) {
  const simulate::Rig rig(rig_file.rig);
  const std::vector<PlannedCapture> captures = ExpandPlan(plan);
  CaptureForecast f;
  f.plan_name = plan.name;
  f.rig_name = rig_name;
  f.images = static_cast<int64_t>(captures.size());
  std::optional<std::pair<Scene, int>> scene;
  for (const PlannedCapture& capture : captures) {
    f.dot_images += capture.key.rfind("dot/", 0) == 0;
    if (!scene || *scene != std::pair(capture.scene, capture.view)) ++f.operator_steps, scene = {capture.scene, capture.view};
  }
  f.frame_time_s = rig_file.frame_time_s;
  f.control_delay_frames = rig_file.control_delay_frames;
  f.duration = Duration(captures, plan, rig_file.frame_time_s, rig_file.control_delay_frames);
  // The camera as `svbtdf acquire` would see it, so that the estimate is acquire's own.
  CameraInfo camera;
  const simulate::CameraIntrinsics& k = rig_file.rig.intrinsics;
  camera.frame_width = k.width;
  camera.frame_height = k.height;
  camera.frame_channels = 3;
  camera.frame_bits = rig_file.rig.sensor.bit_depth;
  camera.window = rig_file.rig.window;
  f.bytes = EstimatedBytes(captures, plan, camera);
  f.image_size = {k.width, k.height};
  if (!camera.window.whole_sensor()) f.sensor_size = {camera.window.sensor_width, camera.window.sensor_height};
  f.eta = plan.rig.eta > 1.0 ? plan.rig.eta : rig_file.eta;

  const std::vector<model::Vec3> dots = DotPositions(plan, rig);
  const simulate::SampleConfig& s = rig_file.rig.sample;
  const double hx = s.width / 2, hy = s.height() / 2;
  f.coverage.push_back(CoverageAt("centre", model::Vec3::Zero(), plan, dots, rig));
  f.coverage.push_back(CoverageAt("corner (-x, +y)", {-hx, hy, 0}, plan, dots, rig));
  f.coverage.push_back(CoverageAt("corner (+x, +y)", {hx, hy, 0}, plan, dots, rig));
  f.coverage.push_back(CoverageAt("corner (-x, -y)", {-hx, -hy, 0}, plan, dots, rig));
  f.coverage.push_back(CoverageAt("corner (+x, -y)", {hx, -hy, 0}, plan, dots, rig));
  const DotCoverage& centre = f.coverage.front();
  for (double roughness : roughnesses) {
    LobeSampling lobe;
    lobe.roughness = roughness;
    lobe.width_deg = LobeWidthDeg(roughness, f.eta, model::Vec3::Zero(), rig);
    lobe.dots_across = centre.spacing_deg > 0 ? lobe.width_deg / centre.spacing_deg : 0.0;
    // A dot must act as a point: its diameter well inside the lobe (docs/capture.md, "Dot size").
    lobe.verdict = lobe.dots_across < kMinDotsAcrossLobe      ? "too sparse"
                   : 10 * centre.dot_radius_deg > lobe.width_deg ? "dots too large"
                                                                  : "ok";
    f.lobes.push_back(lobe);
  }
  return f;
}

std::string FormatForecast(const CaptureForecast& f) {
  std::ostringstream out;
  char line[512];
  const auto put = [&](const char* format, auto... values) {
    std::snprintf(line, sizeof line, format, values...);
    out << line;
  };
  put("plan '%s' on rig '%s'\n", f.plan_name.c_str(), f.rig_name.c_str());
  if (f.exposure_scale != 1.0) put("exposures: the plan's times %.4g (shortest dot exposure set)\n", f.exposure_scale);
  put("images:    %lld (%lld dot images), %d operator steps\n", static_cast<long long>(f.images),
      static_cast<long long>(f.dot_images), f.operator_steps);
  const CaptureDuration& d = f.duration;
  put("duration:  %s: exposing %s, settling %s (%d patterns), exposure changes %s (%d x %d frames); "
      "frame time %.4f s; operator steps not counted\n",
      Clock(d.total_s()).c_str(), Clock(d.exposing_s).c_str(), Clock(d.settling_s).c_str(), d.patterns,
      Clock(d.control_s).c_str(), d.exposure_changes, f.control_delay_frames, f.frame_time_s);
  put("disk:      %.2f GB (images %d x %d", f.bytes / 1e9, f.image_size[0], f.image_size[1]);
  if (f.sensor_size[0] > 0) put(", board views on the whole %d x %d sensor", f.sensor_size[0], f.sensor_size[1]);
  put(", 16-bit RGB before compression)\n");
  put("dots seen from the sample (degrees):\n");
  put("  %-16s %17s %15s %9s %8s %8s %7s\n", "where", "incidence", "through->dot", "in grid", "reach", "spacing",
      "radius");
  for (const DotCoverage& c : f.coverage) {
    put("  %-16s %7.1f .. %5.1f %15.2f %9s %8.1f %8.2f %7.3f\n", c.where.c_str(), c.min_incidence_deg,
        c.max_incidence_deg, c.straight_through_to_nearest_dot_deg, c.straight_through_in_grid ? "yes" : "NO",
        c.reach_deg, c.spacing_deg, c.dot_radius_deg);
  }
  if (!f.lobes.empty()) {
    put("lobes at the centre (GGX, dual-microfacet, eta %.3g; at least %.0f dots across the half-maximum width):\n", f.eta,
        kMinDotsAcrossLobe);
    for (const LobeSampling& lobe : f.lobes) {
      put("  a GGX %g lobe spans %.1f deg = %.1f dots: %s\n", lobe.roughness, lobe.width_deg, lobe.dots_across,
          lobe.verdict.c_str());
    }
  }
  return out.str();
}

}  // namespace svbtdf::acquire
