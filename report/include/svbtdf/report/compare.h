#pragma once
// Scoring a fitted material against the simulator's ground truth (issue 5's metrics, the
// numbers of `svbtdf compare`): alpha and NDF against an analytic truth's parameters, rho_d, and
// the BTDF itself at the rig's dots (held-out and all) against either kind of truth.

#include <cstddef>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "svbtdf/fit/material.h"
#include "svbtdf/simulate/truth.h"

namespace svbtdf::report {

struct CompareOptions {
  // Where the material was read from, as the user spelled it: named in the metrics and errors.
  std::string material_folder;
  // A random subset of at most this many texels keeps large materials quick; the seed makes
  // the subset repeatable.
  int max_texels = 1000;
  uint64_t seed = 1;
};

// A metric with no data (no alpha or NDF in a Monte Carlo truth, no truth energy) is NaN.
struct CompareMetrics {
  std::string material_folder, truth_folder, truth_kind;
  std::string btdf;  // fit::MaterialModelName of the material
  bool truth_has_parameters = false;  // the truth has a true alpha and NDF per texel
  size_t texels_compared = 0;
  double alpha_within_0_05 = 0;  // fraction of the compared texels with |alpha error| <= 0.05
  double alpha_error_median = 0;
  double ndf_rel_l2_median = 0;
  double rho_d_rel_error_median = 0;  // over texels whose true rho_d luminance exceeds 1e-3
  double heldout_rel_rmse = 0;        // of the BTDF luminance over (texel, held-out dot) pairs
  double all_dots_rel_rmse = 0;       // the same over every dot
  size_t heldout_dots = 0;
  bool holdout_recorded = false;  // false: the fit withheld no dots, so every dot counts as held out
  // Per-texel uncertainty (a material with standard errors, format version 3): the fraction of
  // the compared texels whose true value lies within 2 standard errors of the fitted one, per
  // parameter (k_s and rho_d per channel; the NDF by its width, fit::NdfWidth), over the texels
  // whose standard error is known; alpha, k_s, shadowing and NDF need an analytic truth. NaN
  // without.
  double coverage_alpha = std::nan(""), coverage_k_s = std::nan(""), coverage_rho_d = std::nan("");
  double coverage_shadowing = std::nan(""), coverage_ndf_width = std::nan("");
  // The median of |fitted - truth| / se for the same parameters in the same order (alpha, k_s,
  // rho_d, shadowing, NDF width): 0.674 for calibrated normal errors.
  std::array<double, 5> z_median = {std::nan(""), std::nan(""), std::nan(""), std::nan(""), std::nan("")};
  // Spearman rank correlation across the compared texels between the predicted error
  // (prediction_se.exr) and the texel's actual held-out relative RMSE against the truth; and the
  // same for the fit's residual (residual.exr). NaN without.
  double heldout_rank_correlation = std::nan(""), residual_rank_correlation = std::nan("");
  // A slab material (`fit --model slab`) against a Monte Carlo truth: per slab material of the
  // truth, its texels' fitted interfaces against the true ones. Roughness is each side's
  // sqrt(alpha_x alpha_y) (fit::SlabSide::Roughness), axes are (long, short). A true value is NaN
  // where that interface is not a GGX lobe about the normal (the fit's family), so that no number
  // pretends to compare.
  struct SlabRecovery {
    std::string label;
    size_t texels = 0;
    double true_entry = std::nan(""), true_exit = std::nan("");
    double entry_median = std::nan(""), exit_median = std::nan("");  // of the fitted roughnesses
    std::array<double, 2> true_entry_axes = {std::nan(""), std::nan("")}, true_exit_axes = {std::nan(""), std::nan("")};
    std::array<double, 2> entry_axes_median = {std::nan(""), std::nan("")}, exit_axes_median = {std::nan(""), std::nan("")};
    double entry_se_median = std::nan(""), exit_se_median = std::nan("");
    // Fraction of the texels whose fitted roughness lies within 15% of the true one.
    double entry_within_15 = std::nan(""), exit_within_15 = std::nan("");
  };
  std::vector<SlabRecovery> slab_recovery;
  // Any material against a Monte Carlo truth: the held-out relative RMSE over the texels of each of
  // the truth's slab materials (what one model gains or loses on which kind of slab).
  struct TruthSlabError {
    std::string label;
    size_t texels = 0;
    double heldout_rel_rmse = std::nan("");
  };
  std::vector<TruthSlabError> heldout_by_truth_slab;
};

// Spearman's rank correlation of two equally long samples (ties take their mean rank); NaN for
// fewer than 3 pairs or a constant sample.
double SpearmanCorrelation(const std::vector<double>& a, const std::vector<double>& b);

// Throws svbtdf::Error naming options.material_folder when the material and the truth differ in
// size, or when the material records a held-out dot the rig does not have.
CompareMetrics Compare(const fit::Material& material, const simulate::Truth& truth, const CompareOptions& options);

// The metrics as `svbtdf compare --json` writes them (docs/validation.md); NaN becomes null.
nlohmann::json ToJson(const CompareMetrics& metrics);

// The one check that a material and a truth describe the same texels; throws naming the material.
void RequireSameSize(const fit::Material& material, const std::string& material_folder, const simulate::Truth& truth);

}  // namespace svbtdf::report
