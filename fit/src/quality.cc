#include "svbtdf/fit/quality.h"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <string>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/image_io.h"

namespace svbtdf::fit {
namespace fs = std::filesystem;
namespace {

std::string Format(const char* format, ...) __attribute__((format(printf, 1, 2)));
std::string Format(const char* format, ...) {
  char buffer[1024];
  va_list args;
  va_start(args, format);
  std::vsnprintf(buffer, sizeof buffer, format, args);
  va_end(args);
  return buffer;
}

double Percent(int64_t part, int64_t whole) { return whole > 0 ? 100.0 * part / whole : 0.0; }

std::string TexelName(int64_t texel, int width) {
  return Format("(%lld, %lld)", static_cast<long long>(texel % width), static_cast<long long>(texel / width));
}

}  // namespace

std::string QualityWarning::Line() const {
  std::string line = "warning: " + stage + ": " + file + ": " + what;
  if (!figures.empty()) line += " (" + figures + ")";
  if (!likely_cause.empty()) line += "; likely cause: " + likely_cause;
  return line;
}

std::vector<QualityWarning> CheckCalibration(const calib::SessionCalibration& c, const std::string& file) {
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
    std::string figures = Format("residual RMS %.3f mm, max %.3f mm", m.residual_rms_mm, max_mm);
    if (worst >= 0 && m.dots[worst].residual_mm == max_mm) figures += Format(" at dot %lld", static_cast<long long>(worst));
    figures += Format("; %lld of %lld found dots above %.1f mm; limits: RMS %.1f mm, max %.1f mm", static_cast<long long>(far),
                      static_cast<long long>(dots - missing), kMaxDotResidualMm, kMaxDotResidualRmsMm, kMaxDotResidualMm);
    warn("dot-residual", "the dots found in the image are far from the fitted dot grid", figures,
         "the dots may be mislabelled (monitor orientation, or rig.dots.positions_px in session.json not what was "
         "displayed), or the monitor's pose or distance is wrong; light directions, and so the fit, are then wrong");
  }
  if (dots > 0 && missing > kMaxMissingDotFraction * dots) {
    warn("dots-missing", "dots of the grid were not found in the dot image",
         Format("%lld of %lld dots not found (%.1f%%; limit %.0f%%)", static_cast<long long>(missing),
                static_cast<long long>(dots), Percent(missing, dots), 100 * kMaxMissingDotFraction),
         "the exposure of all_dots is too low, or dots fall outside the camera's view or behind the holder; their "
         "positions are extrapolated from the others");
  }

  // Zhang calibration of the camera.
  const calib::CalibrationReport& camera = c.camera;
  if (camera.rms_px > kMaxCameraRmsPx) {
    warn("camera-rms", "the camera calibration's reprojection error is high",
         Format("Zhang reprojection RMS %.3f px over %d views; limit %.1f px", camera.rms_px, camera.used_views(),
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
         Format("%lld of %lld views dropped (limit %.0f%%): ", static_cast<long long>(dropped),
                static_cast<long long>(views), 100 * kMaxDroppedViewFraction) +
             reasons,
         "board not found or far worse than the others: blurred, over- or under-exposed, or partly outside the image; "
         "retake them");
  }
  if (c.sample_plane.rms_px > kMaxSamplePlaneRmsPx) {
    warn("sample-plane-rms", "the holder board's reprojection error is high",
         Format("sample plane reprojection RMS %.3f px; limit %.1f px", c.sample_plane.rms_px, kMaxSamplePlaneRmsPx),
         "the board in sample_plane/v00 is blurred, not flat, or not the board session.json describes "
         "(rig.sample_plane_board); the sample's pose, and every texel's directions, are then off");
  }
  return warnings;
}

std::vector<QualityWarning> CheckSliceStore(const fs::path& processed) {
  std::vector<QualityWarning> warnings;
  const fs::path mask_file = processed / "mask.exr";
  const FloatImage mask = ReadFloatImage(mask_file);
  const int64_t texels = static_cast<int64_t>(mask.width) * mask.height;
  int64_t valid = 0;
  for (int64_t t = 0; t < texels; ++t) valid += mask.pixels[static_cast<size_t>(t) * mask.channels] > 0.5f;
  if (texels > 0 && valid < kMinValidTexelFraction * texels) {
    warnings.push_back({"process", mask_file.string(), "valid-texels", "few texels can be fitted",
                        Format("%lld of %lld texels valid (%.1f%%; minimum %.0f%%)", static_cast<long long>(valid),
                               static_cast<long long>(texels), Percent(valid, texels), 100 * kMinValidTexelFraction),
                        "the exposure is too low (no refractive signal above the noise) or too high (saturated in "
                        "every bracket), or the texel grid reaches past the sample or the camera's window"});
  }

  // Texels with no dot beneath them: reach.exr when the store has it, else the manifest's count.
  const fs::path reach_file = processed / "reach.exr";
  int64_t without = -1, counted = 0;
  fs::path named = reach_file;
  if (fs::exists(reach_file)) {
    const FloatImage reach = ReadFloatImage(reach_file);
    counted = static_cast<int64_t>(reach.width) * reach.height;
    without = 0;
    for (int64_t t = 0; t < counted; ++t) without += !(reach.pixels[static_cast<size_t>(t) * reach.channels] > 0.5f);
  } else {
    named = processed / "processed.json";
    try {
      const nlohmann::json manifest = nlohmann::json::parse(ReadTextFile(named));
      const nlohmann::json statistics = manifest.value("statistics", nlohmann::json::object());
      if (statistics.contains("texels_without_dot_beneath")) {
        without = statistics.at("texels_without_dot_beneath").get<int64_t>();
        counted = statistics.value("texels", texels);
      }
    } catch (const nlohmann::json::exception& e) {
      ThrowFormatError(named.string(), std::string("cannot be read for its statistics: ") + e.what());
    }
  }
  if (without >= 0 && counted > 0 && without > kMaxTexelsWithoutDotFraction * counted) {
    warnings.push_back({"process", named.string(), "texels-without-dot", "texels have no dot beneath them",
                        Format("%lld of %lld texels (%.1f%%; limit %.0f%%) have no dot beneath them",
                               static_cast<long long>(without), static_cast<long long>(counted),
                               Percent(without, counted), 100 * kMaxTexelsWithoutDotFraction),
                        "the dots do not reach beneath the sample: widen the dot grid (rig.dots) past the sample's "
                        "edges; those texels' lobe peaks are never sampled and their fits extrapolate"});
  }
  return warnings;
}

std::vector<QualityWarning> CheckMaterial(const Material& m, const fs::path& folder) {
  std::vector<QualityWarning> warnings;
  const int64_t texels = static_cast<int64_t>(m.width) * m.height;

  // Residuals of the texels' own fits.
  int64_t known = 0, bad = 0;
  std::vector<float> residuals;
  for (int64_t t = 0; t < texels && t < static_cast<int64_t>(m.residual.pixels.size()); ++t) {
    const float r = m.residual.pixels[t];
    if (!(r >= 0)) continue;  // -1: not known
    ++known;
    bad += r > kMaxTexelRelativeRmse;
    residuals.push_back(r);
  }
  if (known > 0 && bad > kMaxBadResidualFraction * known) {
    std::nth_element(residuals.begin(), residuals.begin() + residuals.size() / 2, residuals.end());
    const double median = residuals[residuals.size() / 2];
    const double worst = *std::max_element(residuals.begin(), residuals.end());
    warnings.push_back({"fit", (folder / "residual.exr").string(), "fit-residual",
                        "the fitted model does not match the samples of many texels",
                        Format("%lld of %lld texels (%.1f%%; limit %.0f%%) fit with a relative RMSE above %.2f; median "
                               "%.3f, max %.3f",
                               static_cast<long long>(bad), static_cast<long long>(known), Percent(bad, known),
                               100 * kMaxBadResidualFraction, kMaxTexelRelativeRmse, median, worst),
                        m.model == MaterialModel::kWalterGgx
                            ? "the single-interface baseline (--model ggx) cannot describe this slab's lobes (it "
                              "refracts once; expected for a slab with two rough interfaces: fit --model dual), or "
                              "wrong light directions (see the calibration's dot residuals)"
                            : "wrong light directions (the dots may be mislabelled or misplaced: see the calibration's "
                              "dot residuals), samples too noisy (the exposure is too low), or a material the model "
                              "cannot describe"});
  }

  // k_s: a transmission scale, about 1 for a physical slab.
  // Each texel's largest channel; NaN ranks above everything (and is shown as nan).
  const auto rank = [](double k) { return std::isnan(k) ? HUGE_VAL : k; };
  int64_t implausible = 0, worst_texel = -1;
  double worst_k_s = 0;
  for (int64_t t = 0; t < texels && 3 * t + 2 < static_cast<int64_t>(m.k_s.pixels.size()); ++t) {
    double k = m.k_s.pixels[3 * t];
    for (int c = 1; c < 3; ++c) {
      const double v = m.k_s.pixels[3 * t + c];
      if (rank(v) > rank(k)) k = v;
    }
    if (std::isfinite(k) && k <= kMaxPlausibleKs) continue;
    ++implausible;
    if (worst_texel < 0 || rank(k) > rank(worst_k_s)) {
      worst_texel = t;
      worst_k_s = k;
    }
  }
  if (implausible > 0) {
    warnings.push_back({"fit", (folder / "k_s.exr").string(), "k_s-implausible", "k_s is implausibly large",
                        Format("%lld of %lld texels (%.1f%%) have k_s above %.0e or not finite; max %.3g at texel %s",
                               static_cast<long long>(implausible), static_cast<long long>(texels),
                               Percent(implausible, texels), kMaxPlausibleKs, worst_k_s,
                               TexelName(worst_texel, m.width).c_str()),
                        "the fitted NDF put its mass where no dot looks and k_s compensates: the dots may be "
                        "misplaced (see the calibration), or they do not sample the lobe's peak (widen or densify "
                        "the dot grid)"});
  }

  // alpha stuck at its bounds (dual-microfacet only: the baseline has no alpha).
  if (m.model == MaterialModel::kDualMicrofacet && texels > 0 && static_cast<int64_t>(m.alpha.pixels.size()) >= texels) {
    int64_t at_zero = 0, at_one = 0;
    for (int64_t t = 0; t < texels; ++t) {
      const float a = m.alpha.pixels[t];
      at_zero += a <= kAlphaBoundTolerance;
      at_one += a >= 1 - kAlphaBoundTolerance;
    }
    if (at_zero + at_one >= kMaxAlphaAtBoundFraction * texels) {
      warnings.push_back({"fit", (folder / "alpha.exr").string(), "alpha-at-bounds", "alpha is at its bounds everywhere",
                          Format("%.1f%% of texels at alpha = 0, %.1f%% at alpha = 1 (limit %.0f%% together)",
                                 Percent(at_zero, texels), Percent(at_one, texels), 100 * kMaxAlphaAtBoundFraction),
                          "the samples do not tell the two configurations apart (a dot grid too narrow to see the "
                          "lobe's shape) or the fit failed; alpha is then meaningless"});
    }
  }

  // Representatives that could not be fitted (they borrowed a neighbour's fit).
  const nlohmann::json statistics = m.provenance.value("statistics", nlohmann::json::object());
  const int64_t reps = statistics.value("representatives", int64_t{0});
  const int64_t failed = statistics.value("failed_fits", int64_t{0});
  if (reps > 0 && failed > kMaxFailedFitFraction * reps) {
    warnings.push_back({"fit", (folder / "material.json").string(), "failed-fits", "many representatives could not be fitted",
                        Format("%lld of %lld representatives failed (limit %.0f%%)", static_cast<long long>(failed),
                               static_cast<long long>(reps), 100 * kMaxFailedFitFraction),
                        "too few usable samples per texel: the exposure is too low or too high, or the dots do not "
                        "reach beneath the sample"});
  }
  return warnings;
}

nlohmann::json QualityToJson(const std::vector<QualityWarning>& warnings) {
  nlohmann::json list = nlohmann::json::array();
  for (const QualityWarning& w : warnings) {
    list.push_back({{"stage", w.stage},
                    {"file", w.file},
                    {"check", w.check},
                    {"what", w.what},
                    {"figures", w.figures},
                    {"likely_cause", w.likely_cause}});
  }
  return {
      {"format", "svbtdf-quality"},
      {"version", kQualityFormatVersion},
      {"thresholds",
       {{"dot_residual_max_mm", kMaxDotResidualMm},
        {"dot_residual_rms_mm", kMaxDotResidualRmsMm},
        {"missing_dot_fraction", kMaxMissingDotFraction},
        {"camera_rms_px", kMaxCameraRmsPx},
        {"sample_plane_rms_px", kMaxSamplePlaneRmsPx},
        {"dropped_view_fraction", kMaxDroppedViewFraction},
        {"min_valid_texel_fraction", kMinValidTexelFraction},
        {"texels_without_dot_fraction", kMaxTexelsWithoutDotFraction},
        {"texel_relative_rmse", kMaxTexelRelativeRmse},
        {"bad_residual_fraction", kMaxBadResidualFraction},
        {"k_s_max", kMaxPlausibleKs},
        {"alpha_at_bound_fraction", kMaxAlphaAtBoundFraction},
        {"failed_fit_fraction", kMaxFailedFitFraction}}},
      {"warnings", list},
  };
}

std::vector<QualityWarning> QualityFromJson(const nlohmann::json& json, const std::string& source) {
  std::vector<QualityWarning> warnings;
  try {
    if (json.at("format") != "svbtdf-quality") ThrowFormatError(source, "is not an svbtdf quality file");
    const int version = json.at("version").get<int>();
    if (version < 1 || version > kQualityFormatVersion) {
      ThrowFormatError(source, "has quality format version " + std::to_string(version) + "; this svbtdf reads version " +
                                   std::to_string(kQualityFormatVersion));
    }
    for (const nlohmann::json& w : json.at("warnings")) {
      warnings.push_back({w.at("stage").get<std::string>(), w.at("file").get<std::string>(),
                          w.value("check", std::string()), w.at("what").get<std::string>(),
                          w.value("figures", std::string()), w.value("likely_cause", std::string())});
    }
  } catch (const nlohmann::json::exception& e) {
    ThrowFormatError(source, std::string("misses a field or has a wrong type: ") + e.what());
  }
  return warnings;
}

void WriteQuality(const fs::path& material_folder, const std::vector<QualityWarning>& warnings) {
  WriteTextAtomically(material_folder / "quality.json", QualityToJson(warnings).dump(2) + "\n");
}

bool ReadQuality(const fs::path& material_folder, std::vector<QualityWarning>* warnings) {
  const fs::path path = material_folder / "quality.json";
  if (!fs::exists(path)) return false;
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(ReadTextFile(path));
  } catch (const nlohmann::json::exception& e) {
    ThrowFormatError(path.string(), std::string("is not valid JSON: ") + e.what());
  }
  *warnings = QualityFromJson(json, path.string());
  return true;
}

}  // namespace svbtdf::fit
