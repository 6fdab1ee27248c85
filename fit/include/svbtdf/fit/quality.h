#pragma once
// Quality checks of the pipeline's outputs (docs/quality.md): each stage's output is inspected
// for figures that say the result is badly wrong (dots far off the fitted grid, texels with no
// dot beneath them, fits that do not match their samples, implausible k_s), and every finding is
// a QualityWarning naming the stage, the file, the figures and the likely cause.
//
// `svbtdf calibrate`, `process`, `fit` and `run` print them on stderr (one line each, starting
// "warning:"); `fit` and `run` record every stage's warnings in MATERIAL/quality.json, which
// `svbtdf report` shows at the top of its page; `--strict` turns them into exit code 4.
//
// The checks only read the outputs: a stage's warnings are the same whenever they are computed.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "svbtdf/fit/material.h"
#include "svbtdf/fit/texel_fit.h"

namespace svbtdf::fit {

inline constexpr int kQualityFormatVersion = 1;
// The exit code of a command run with --strict whose output drew quality warnings (3 is taken:
// `svbtdf acquire` and `session verify` use it for an incomplete session).
inline constexpr int kQualityWarningExitCode = 4;

struct QualityWarning {
  std::string stage;         // "calibrate" | "process" | "fit"
  std::string file;          // the output inspected (calibration.json, mask.exr, residual.exr, ...)
  std::string check;         // short stable identifier, e.g. "dot-residual" (docs/quality.md)
  std::string what;          // what is wrong, in words
  std::string figures;       // the numbers behind it, with the threshold
  std::string likely_cause;  // what probably went wrong and what to do

  // "warning: calibrate: FILE: WHAT (FIGURES); likely cause: LIKELY_CAUSE"
  std::string Line() const;
};

// printf into a string: a warning's figures.
std::string FormatFigures(const char* format, ...) __attribute__((format(printf, 1, 2)));
// 100 part / whole, 0 for an empty whole.
double Percent(int64_t part, int64_t whole);

// --- Thresholds (docs/quality.md says why each is where it is) -----------------------------------

// Calibration. A dot's centroid is located to about 0.02 mm on the monitor plane (blob noise; the
// simulated presets' grid residual RMS is 0.014 mm, their worst dot 0.11-0.15 mm): residuals many
// times that mean the dots are not where the grid says (mislabelled, a wrong monitor pose).
inline constexpr double kMaxDotResidualMm = 0.3;
inline constexpr double kMaxDotResidualRmsMm = 0.1;
// Dots with no blob matched: their position is extrapolated from the fitted grid. A few may be
// hidden (a speck, the holder's edge); more than this fraction says the dot image is wrong.
inline constexpr double kMaxMissingDotFraction = 0.05;
// Zhang reprojection RMS: a sharp, well-lit board calibrates to a few tenths of a pixel
// (simulated presets: below 0.1 px); above 1 px the corners or the lens model are off.
inline constexpr double kMaxCameraRmsPx = 1.0;
// Reprojection RMS of the holder board in sample_plane/v00 (same reasoning as the camera's).
inline constexpr double kMaxSamplePlaneRmsPx = 1.0;
// Board views dropped as outliers or not found: a few are normal; more than this fraction of
// the views means the board photos (focus, motion, exposure) are poor.
inline constexpr double kMaxDroppedViewFraction = 0.25;

// Processing. Every texel of the grid lies on the sample; texels masked out (fewer than 8 valid
// dots or no refractive signal) have no fit of their own.
inline constexpr double kMinValidTexelFraction = 0.9;
// Texels with no dot beneath them (reach.exr == 0) see only grazing light: their lobe peak is
// never sampled and the fit extrapolates it.
inline constexpr double kMaxTexelsWithoutDotFraction = 0.05;
// The flat white frame's noise (processed.json `white_exitance_noise`, relative, per texel)
// scales each texel's whole slice, k_s and rho_d alike. The presets measure 0.17-0.20%, already
// most of rho_d's error there (the floor's own noise: 0.035%); at 1% it is the largest error of
// every texel's scale and the k_s and rho_d maps show the frame's grain.
inline constexpr double kMaxWhiteExitanceNoise = 0.01;

// Sampling. A lobe whose half maximum spans fewer than two dots across is seen by one row of
// dots: its width across, and with it alpha (which the lobe's shape decides) and the NDF there,
// are not determined by the samples. On stores synthesised with GGX lobes 0.40 long (eta 1.4, 1%
// noise, docs/quality.md): 0.05 across at 1.1-1.6 degree spacing fitted alpha within 0.05 on 6%
// of the texels, 0.10 across on 100%; twice the dots brought 0.05 to 100%.
inline constexpr double kMinDotsAcrossLobe = 2.0;
// ... and more than this fraction of the texels checked below it is a capture too sparse for
// the material.
inline constexpr double kMaxUndersampledLobeFraction = 0.1;
// The texels read for that check: at most this many tiles spread over the store (a tile is about
// 10 MB at 1,600 dots), and of their texels about kLobeCheckTexels evenly (every one of a small
// store's).
inline constexpr int kLobeCheckTiles = 16;
inline constexpr int kLobeCheckTexels = 2048;

// Fit. The relative RMSE of a good fit is the capture's noise plus the model's error, a few
// percent (tiny preset: median 0.014, max 0.11; small: 0.010, max 0.05); 20% means the model does
// not describe the samples.
inline constexpr double kMaxTexelRelativeRmse = 0.2;
// ... and more than this fraction of the texels with a known residual above it is a bad material.
inline constexpr double kMaxBadResidualFraction = 0.1;
// k_s scales the refractive lobe; a physical slab transmits at most about 1 (simulated presets:
// 0.3-1.5). Values above this compensate for an NDF whose mass sits where no dot looks.
inline constexpr double kMaxPlausibleKs = 1e3;
// Texels whose alpha sits at 0 or 1 (within this) — "everywhere" means this fraction of them.
inline constexpr double kAlphaBoundTolerance = 1e-3;
inline constexpr double kMaxAlphaAtBoundFraction = 0.99;
// Representatives whose fit failed borrow the nearest successful one's. One of the `tiny` preset's
// 10 does (its texels are refined on their own samples afterwards); a quarter is a bad capture.
inline constexpr double kMaxFailedFitFraction = 0.25;

// --- Checks ------------------------------------------------------------------------------------

// How many dots sample a texel's lobe across its narrowest direction at half maximum:
// sqrt(1 + 12 var / s^2), where var is the smaller eigenvalue of the covariance of the light
// directions whose rho is at least half the slice's largest (in the plane perpendicular to the
// brightest dot's direction) and s the dot spacing there (the angle from the brightest dot to
// its nearest). n parallel rows of dots above half maximum give n; one dot or one row gives 1.
// 0 for a slice without a positive sample.
double DotsAcrossLobe(const TexelSlice& slice);

// Reads PROCESSED/mask.exr, and PROCESSED/reach.exr or processed.json's
// statistics.texels_without_dot_beneath when present (the check is skipped when neither is). When
// the folder holds samples (samples.f16), also the lobes of a sample of its texels
// (DotsAcrossLobe; kLobeCheckTiles tiles).
std::vector<QualityWarning> CheckSliceStore(const std::filesystem::path& processed);
// `folder` is how the warnings name the material's files.
std::vector<QualityWarning> CheckMaterial(const Material& material, const std::filesystem::path& folder);

// --- MATERIAL/quality.json ---------------------------------------------------------------------

nlohmann::json QualityToJson(const std::vector<QualityWarning>& warnings);
// Throws svbtdf::Error(kFormat) naming `source` for a wrong format, version or field.
std::vector<QualityWarning> QualityFromJson(const nlohmann::json& json, const std::string& source);
// Writes MATERIAL/quality.json atomically (replacing an earlier one).
void WriteQuality(const std::filesystem::path& material_folder, const std::vector<QualityWarning>& warnings);
// Reads MATERIAL/quality.json; false when the material has none (written before the checks existed).
bool ReadQuality(const std::filesystem::path& material_folder, std::vector<QualityWarning>* warnings);

}  // namespace svbtdf::fit
