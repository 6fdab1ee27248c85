#include "svbtdf/process/calibration_quality.h"

#include <algorithm>
#include <cmath>

namespace svbtdf::process {

using namespace fit;  // the warning vocabulary and its thresholds (fit/quality.h)

std::vector<fit::QualityWarning> CheckCalibration(const calib::SessionCalibration& c, const std::string& file) {
  std::vector<QualityWarning> warnings;
  const auto warn = [&](std::string check, std::string what, std::string figures, std::string cause) {
    warnings.push_back({"calibrate", file, std::move(check), std::move(what), std::move(figures), std::move(cause)});
  };

  // The dots against the fitted grid.
  const calib::MonitorCalibration& m = c.monitor;
  const int64_t dots = static_cast<int64_t>(m.dots.size());
  int64_t missing = 0, far = 0;
  int64_t worst = -1;
  for (int64_t q = 0; q < dots; ++q) {
    const double r = m.dots[q].residual_mm;
    if (r < 0) {
      ++missing;
      continue;
    }
    if (r > kMaxDotResidualMm) ++far;
    if (worst < 0 || r > m.dots[worst].residual_mm) worst = q;
  }
  const double max_mm = std::max(m.residual_max_mm, worst >= 0 ? m.dots[worst].residual_mm : 0.0);
  if (max_mm > kMaxDotResidualMm || m.residual_rms_mm > kMaxDotResidualRmsMm) {
    std::string figures = FormatFigures("residual RMS %.3f mm, max %.3f mm", m.residual_rms_mm, max_mm);
    if (worst >= 0 && m.dots[worst].residual_mm == max_mm) figures += FormatFigures(" at dot %lld", static_cast<long long>(worst));
    figures += FormatFigures("; %lld of %lld found dots above %.1f mm; limits: RMS %.1f mm, max %.1f mm", static_cast<long long>(far),
                      static_cast<long long>(dots - missing), kMaxDotResidualMm, kMaxDotResidualRmsMm, kMaxDotResidualMm);
    warn("dot-residual", "the dots found in the image are far from the fitted dot grid", figures,
         "the dots may be mislabelled (monitor orientation, or rig.dots.positions_px in session.json not what was "
         "displayed), or the monitor's pose or distance is wrong; light directions, and so the fit, are then wrong");
  }
  if (dots > 0 && missing > kMaxMissingDotFraction * dots) {
    warn("dots-missing", "dots of the grid were not found in the dot image",
         FormatFigures("%lld of %lld dots not found (%.1f%%; limit %.0f%%)", static_cast<long long>(missing),
                static_cast<long long>(dots), Percent(missing, dots), 100 * kMaxMissingDotFraction),
         "the exposure of all_dots is too low, or dots fall outside the camera's view or behind the holder; their "
         "positions are extrapolated from the others");
  }

  // Zhang calibration of the camera.
  const calib::CalibrationReport& camera = c.camera;
  if (camera.rms_px > kMaxCameraRmsPx) {
    warn("camera-rms", "the camera calibration's reprojection error is high",
         FormatFigures("Zhang reprojection RMS %.3f px over %d views; limit %.1f px", camera.rms_px, camera.used_views(),
                kMaxCameraRmsPx),
         "blurred or badly lit board views, a --board specification (size, square) that does not match the printed "
         "board, or a board that is not flat");
  }
  const int64_t views = static_cast<int64_t>(camera.views.size());
  const int64_t dropped = views - camera.used_views();
  if (views > 0 && dropped > kMaxDroppedViewFraction * views) {
    std::string reasons;
    int listed = 0;
    for (const calib::ViewReport& view : camera.views) {
      if (view.used || listed == 3) continue;
      reasons += (listed++ ? ", " : "") + view.source + ": " + view.dropped_because;
    }
    if (dropped > listed) reasons += ", ...";
    warn("views-dropped", "many board views were dropped from the camera calibration",
         FormatFigures("%lld of %lld views dropped (limit %.0f%%): ", static_cast<long long>(dropped),
                static_cast<long long>(views), 100 * kMaxDroppedViewFraction) +
             reasons,
         "board not found or far worse than the others: blurred, over- or under-exposed, or partly outside the image; "
         "retake them");
  }
  if (c.sample_plane.rms_px > kMaxSamplePlaneRmsPx) {
    warn("sample-plane-rms", "the holder board's reprojection error is high",
         FormatFigures("sample plane reprojection RMS %.3f px; limit %.1f px", c.sample_plane.rms_px, kMaxSamplePlaneRmsPx),
         "the board in sample_plane/v00 is blurred, not flat, or not the board session.json describes "
         "(rig.sample_plane_board); the sample's pose, and every texel's directions, are then off");
  }
  return warnings;
}

}  // namespace svbtdf::process
