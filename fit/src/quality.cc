#include "svbtdf/fit/quality.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <string>

#include <Eigen/Eigenvalues>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/json.h"
#include "svbtdf/common/image_io.h"
#include "svbtdf/fit/slice_store.h"
#include "svbtdf/fit/slice_store_format.h"

namespace svbtdf::fit {
namespace fs = std::filesystem;

std::string FormatFigures(const char* format, ...) {
  char buffer[1024];
  va_list args;
  va_start(args, format);
  std::vsnprintf(buffer, sizeof buffer, format, args);
  va_end(args);
  return buffer;
}

double Percent(int64_t part, int64_t whole) { return whole > 0 ? 100.0 * part / whole : 0.0; }

namespace {

// The likely causes of a poor fit, by what the model can describe.
const char* ResidualCause(MaterialModel model) {
  switch (model) {
    case MaterialModel::kWalterGgx:
      return "the single-interface baseline (--model ggx) cannot describe this slab's lobes (it refracts once; "
             "expected for a slab with two rough interfaces: fit --model dual), or wrong light directions (see the "
             "calibration's dot residuals)";
    case MaterialModel::kSlab:
      return "an interface the slab model cannot describe (a tilted or skewed lobe, or one far from GGX: fit --model "
             "dual), or wrong light directions (see the calibration's dot residuals)";
    case MaterialModel::kDualMicrofacet:
      break;
  }
  return "wrong light directions (the dots may be mislabelled or misplaced: see the calibration's dot residuals), "
         "samples too noisy (the exposure is too low), or a material the model cannot describe";
}

std::string TexelName(int64_t texel, int width) {
  return FormatFigures("(%lld, %lld)", static_cast<long long>(texel % width), static_cast<long long>(texel / width));
}

// Lobes narrower than the dot spacing, on a sample of the store's texels (DotsAcrossLobe).
void CheckLobeSampling(const fs::path& processed, std::vector<QualityWarning>* warnings) {
  const SliceStore store = SliceStore::Open(processed);
  const int64_t texels = store.geometry().num_texels();
  const int tile_texels = store.info().tile_texels;
  const int64_t tiles = (texels + tile_texels - 1) / tile_texels;
  const int64_t checked_tiles = std::min<int64_t>(tiles, kLobeCheckTiles);
  const int64_t stride = std::max<int64_t>(1, checked_tiles * tile_texels / kLobeCheckTexels);
  std::vector<float> samples;
  std::vector<double> across;
  for (int64_t i = 0; i < checked_tiles; ++i) {
    const int64_t tile = checked_tiles > 1 ? i * (tiles - 1) / (checked_tiles - 1) : 0;
    store.ReadTile(tile, &samples);
    for (int64_t t = tile * tile_texels; t < std::min(texels, (tile + 1) * tile_texels); t += stride) {
      if (!(store.mask().pixels[static_cast<size_t>(t) * store.mask().channels] > 0.5f)) continue;
      const double a = DotsAcrossLobe(store.MakeTexelSlice(t, samples));
      if (a > 0) across.push_back(a);
    }
  }
  const auto under = std::count_if(across.begin(), across.end(), [](double a) { return a < kMinDotsAcrossLobe; });
  if (across.empty() || under <= kMaxUndersampledLobeFraction * static_cast<double>(across.size())) return;
  std::nth_element(across.begin(), across.begin() + across.size() / 2, across.end());
  warnings->push_back(
      {"process", (processed / "samples.f16").string(), "lobe-undersampled", "the dots are too sparse for the lobes",
       FormatFigures("%lld of %lld texels checked (%.1f%%; limit %.0f%%) have fewer than %.0f dots across the half "
                     "maximum of their lobe; median %.2f",
                     static_cast<long long>(under), static_cast<long long>(across.size()),
                     Percent(under, static_cast<int64_t>(across.size())), 100 * kMaxUndersampledLobeFraction,
                     kMinDotsAcrossLobe, across[across.size() / 2]),
       "the material's lobes are narrower than the dot spacing: alpha and the NDF's width across the lobe are "
       "not determined by these samples; capture again with denser dots (svbtdf plan --roughness shows the "
       "spacing a lobe needs)"});
}

}  // namespace

std::string QualityWarning::Line() const {
  std::string line = "warning: " + stage + ": " + file + ": " + what;
  if (!figures.empty()) line += " (" + figures + ")";
  if (!likely_cause.empty()) line += "; likely cause: " + likely_cause;
  return line;
}

double DotsAcrossLobe(const TexelSlice& slice) {
  const size_t n = std::min(slice.light.size(), slice.rho.size());
  size_t peak = n;
  for (size_t k = 0; k < n; ++k) {
    if (slice.rho[k] > 0 && (peak == n || slice.rho[k] > slice.rho[peak])) peak = k;
  }
  if (peak == n) return 0.0;
  // Coordinates in the plane perpendicular to the brightest dot's direction (angles, for the
  // small offsets that matter here).
  const model::Vec3 centre = slice.light[peak].normalized();
  const model::Vec3 any = std::abs(centre.x()) < 0.9 ? model::Vec3::UnitX() : model::Vec3::UnitY();
  const model::Vec3 e1 = centre.cross(any).normalized(), e2 = centre.cross(e1);
  double nearest_cosine = -HUGE_VAL;  // of the nearest other dot: one acos after the loop, not one per dot
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  Eigen::Matrix2d second = Eigen::Matrix2d::Zero();
  int bright = 0;
  for (size_t k = 0; k < n; ++k) {
    const model::Vec3 d = slice.light[k].normalized();
    if (k != peak) nearest_cosine = std::max(nearest_cosine, d.dot(centre));
    if (!(slice.rho[k] >= 0.5 * slice.rho[peak])) continue;
    const Eigen::Vector2d x(d.dot(e1), d.dot(e2));
    mean += x;
    second += x * x.transpose();
    ++bright;
  }
  const double spacing = nearest_cosine > -HUGE_VAL ? std::acos(std::clamp(nearest_cosine, -1.0, 1.0)) : HUGE_VAL;
  if (bright < 2 || !(spacing > 0) || !std::isfinite(spacing)) return 1.0;
  mean /= bright;
  const Eigen::Matrix2d covariance = second / bright - mean * mean.transpose();
  const double narrowest = std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(covariance).eigenvalues()[0]);
  return std::sqrt(1.0 + 12.0 * narrowest / (spacing * spacing));
}

namespace {

// The flat white frame's noise as the processing measured it (stores written before it have none).
void CheckWhiteExitanceNoise(const fs::path& manifest_file, std::vector<QualityWarning>* warnings) {
  const std::array<double, 3> noise =
      store::WhiteExitanceNoiseFromManifest(common::ReadJsonFile(manifest_file), manifest_file.string());
  const double worst = *std::max_element(noise.begin(), noise.end());
  if (!(worst > kMaxWhiteExitanceNoise)) return;
  warnings->push_back({"process", manifest_file.string(), "flat-white-noise", "the flat white frame is noisy",
                       FormatFigures("its noise is %.2f%% / %.2f%% / %.2f%% (R / G / B) per texel; limit %.0f%%",
                                     100 * noise[0], 100 * noise[1], 100 * noise[2], 100 * kMaxWhiteExitanceNoise),
                       "every texel's k_s and rho_d carry it (it divides all of a texel's samples): capture "
                       "flat_white again with a longer exposure (flat_white_exposure_s), close to the top of the "
                       "camera's range without saturating"});
}

}  // namespace

std::vector<QualityWarning> CheckSliceStore(const fs::path& processed) {
  std::vector<QualityWarning> warnings;
  const fs::path mask_file = processed / "mask.exr";
  const common::FloatImage mask = common::ReadFloatImage(mask_file);
  const int64_t texels = static_cast<int64_t>(mask.width) * mask.height;
  int64_t valid = 0;
  for (int64_t t = 0; t < texels; ++t) valid += mask.pixels[static_cast<size_t>(t) * mask.channels] > 0.5f;
  if (texels > 0 && valid < kMinValidTexelFraction * texels) {
    warnings.push_back({"process", mask_file.string(), "valid-texels", "few texels can be fitted",
                        FormatFigures("%lld of %lld texels valid (%.1f%%; minimum %.0f%%)", static_cast<long long>(valid),
                               static_cast<long long>(texels), Percent(valid, texels), 100 * kMinValidTexelFraction),
                        "the exposure is too low (no refractive signal above the noise) or too high (saturated in "
                        "every bracket), or the texel grid reaches past the sample or the camera's window"});
  }

  // Texels with no dot beneath them: reach.exr when the store has it, else the manifest's count.
  const fs::path reach_file = processed / "reach.exr";
  int64_t without = -1, counted = 0;
  fs::path named = reach_file;
  if (fs::exists(reach_file)) {
    const common::FloatImage reach = common::ReadFloatImage(reach_file);
    counted = static_cast<int64_t>(reach.width) * reach.height;
    without = 0;
    for (int64_t t = 0; t < counted; ++t) without += !(reach.pixels[static_cast<size_t>(t) * reach.channels] > 0.5f);
  } else {
    named = processed / "processed.json";
    try {
      const nlohmann::json manifest = common::ReadJsonFile(named);
      const nlohmann::json statistics = manifest.value("statistics", nlohmann::json::object());
      if (statistics.contains("texels_without_dot_beneath")) {
        without = statistics.at("texels_without_dot_beneath").get<int64_t>();
        counted = statistics.value("texels", texels);
      }
    } catch (const nlohmann::json::exception& e) {
      common::ThrowFormatError(named.string(), std::string("cannot be read for its statistics: ") + e.what());
    }
  }
  if (without >= 0 && counted > 0 && without > kMaxTexelsWithoutDotFraction * counted) {
    warnings.push_back({"process", named.string(), "texels-without-dot", "texels have no dot beneath them",
                        FormatFigures("%lld of %lld texels (%.1f%%; limit %.0f%%) have no dot beneath them",
                               static_cast<long long>(without), static_cast<long long>(counted),
                               Percent(without, counted), 100 * kMaxTexelsWithoutDotFraction),
                        "the dots do not reach beneath the sample: widen the dot grid (rig.dots) past the sample's "
                        "edges; those texels' lobe peaks are never sampled and their fits extrapolate"});
  }
  CheckWhiteExitanceNoise(processed / "processed.json", &warnings);
  if (fs::exists(processed / "samples.f16")) CheckLobeSampling(processed, &warnings);
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
                        FormatFigures("%lld of %lld texels (%.1f%%; limit %.0f%%) fit with a relative RMSE above %.2f; median "
                               "%.3f, max %.3f",
                               static_cast<long long>(bad), static_cast<long long>(known), Percent(bad, known),
                               100 * kMaxBadResidualFraction, kMaxTexelRelativeRmse, median, worst),
                        ResidualCause(m.model)});
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
                        FormatFigures("%lld of %lld texels (%.1f%%) have k_s above %.0e or not finite; max %.3g at texel %s",
                               static_cast<long long>(implausible), static_cast<long long>(texels),
                               Percent(implausible, texels), kMaxPlausibleKs, worst_k_s,
                               TexelName(worst_texel, m.width).c_str()),
                        "the fitted NDF put its mass where no dot looks and k_s compensates: the dots may be "
                        "misplaced (see the calibration), they may not sample the lobe's peak (widen or densify "
                        "the dot grid), or the sample is a slab the model cannot describe (try svbtdf fit "
                        "--model slab)"});
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
                          FormatFigures("%.1f%% of texels at alpha = 0, %.1f%% at alpha = 1 (limit %.0f%% together)",
                                 Percent(at_zero, texels), Percent(at_one, texels), 100 * kMaxAlphaAtBoundFraction),
                          "the samples do not tell the two configurations apart (a dot grid too narrow to see the "
                          "lobe's shape) or the fit failed; alpha is then meaningless"});
    }
  }

  // Representatives that could not be fitted (they borrowed a neighbour's fit).
  // (The provenance is free-form: a count that is not an integer is as good as none.)
  const nlohmann::json statistics = m.provenance.value("statistics", nlohmann::json::object());
  const auto count = [&](const char* key) {
    return statistics.is_object() && statistics.contains(key) ? common::IntegerIfFits<int64_t>(statistics[key]).value_or(0) : 0;
  };
  const int64_t reps = count("representatives");
  const int64_t failed = count("failed_fits");
  if (reps > 0 && failed > kMaxFailedFitFraction * reps) {
    warnings.push_back({"fit", (folder / "material.json").string(), "failed-fits", "many representatives could not be fitted",
                        FormatFigures("%lld of %lld representatives failed (limit %.0f%%)", static_cast<long long>(failed),
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
        {"failed_fit_fraction", kMaxFailedFitFraction},
        {"min_dots_across_lobe", kMinDotsAcrossLobe},
        {"undersampled_lobe_fraction", kMaxUndersampledLobeFraction}}},
      {"warnings", list},
  };
}

std::vector<QualityWarning> QualityFromJson(const nlohmann::json& json, const std::string& source) {
  std::vector<QualityWarning> warnings;
  try {
    if (json.at("format") != "svbtdf-quality") common::ThrowFormatError(source, "is not an svbtdf quality file");
    const int version = common::IntegerAt(json, "version", source);
    if (version < 1 || version > kQualityFormatVersion) {
      common::ThrowFormatError(source, "has quality format version " + std::to_string(version) + "; this svbtdf reads version " +
                                   std::to_string(kQualityFormatVersion));
    }
    for (const nlohmann::json& w : json.at("warnings")) {
      warnings.push_back({w.at("stage").get<std::string>(), w.at("file").get<std::string>(),
                          w.value("check", std::string()), w.at("what").get<std::string>(),
                          w.value("figures", std::string()), w.value("likely_cause", std::string())});
    }
  } catch (const nlohmann::json::exception& e) {
    common::ThrowFormatError(source, std::string("misses a field or has a wrong type: ") + e.what());
  }
  return warnings;
}

void WriteQuality(const fs::path& material_folder, const std::vector<QualityWarning>& warnings) {
  common::WriteTextAtomically(material_folder / "quality.json", QualityToJson(warnings).dump(2) + "\n");
}

bool ReadQuality(const fs::path& material_folder, std::vector<QualityWarning>* warnings) {
  const fs::path path = material_folder / "quality.json";
  if (!fs::exists(path)) return false;
  *warnings = QualityFromJson(common::ReadJsonFile(path), path.string());
  return true;
}

}  // namespace svbtdf::fit
