#include "svbtdf/report/compare.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "svbtdf/common/error.h"
#include "svbtdf/common/progress.h"
#include "svbtdf/common/statistics.h"
#include "svbtdf/fit/ndf_error.h"

namespace svbtdf::report {
namespace {

// Sums of squared errors and of squared truths of the luminance over (texel, dot) pairs.
struct RelativeRmse {
  double error = 0, norm = 0;
  void Add(double fitted, double truth) {
    error += model::Square(fitted - truth);
    norm += model::Square(truth);
  }
  double Value() const { return norm > 0 ? std::sqrt(error / norm) : std::nan(""); }
};

// The dots whose BTDF error counts as held out: those the fit recorded, or every dot when the
// fit withheld none. Returns one flag per rig dot.
std::vector<bool> HeldOutDots(const fit::Material& material, const CompareOptions& options, size_t rig_dots,
                              CompareMetrics& metrics) {
  std::vector<int> dots;
  const nlohmann::json& provenance = material.provenance;
  metrics.holdout_recorded = provenance.contains("holdout") && provenance["holdout"].contains("dots");
  if (metrics.holdout_recorded) {
    dots = provenance["holdout"]["dots"].get<std::vector<int>>();
  } else {
    for (size_t q = 0; q < rig_dots; ++q) dots.push_back(static_cast<int>(q));
  }
  std::vector<bool> held_out(rig_dots, false);
  for (int q : dots) {
    if (q < 0 || q >= static_cast<int>(rig_dots)) {
      common::ThrowFormatError(options.material_folder,
                       "records held-out dot " + std::to_string(q) + ", which the rig does not have");
    }
    held_out[q] = true;
  }
  metrics.heldout_dots = dots.size();
  return held_out;
}

// A seeded random subset of the texel indices, at most max_texels (and at least one) long.
std::vector<int> TexelSubset(const fit::Material& material, const CompareOptions& options) {
  std::vector<int> texels(static_cast<size_t>(material.width) * material.height);
  for (size_t t = 0; t < texels.size(); ++t) texels[t] = static_cast<int>(t);
  std::mt19937_64 rng(options.seed);
  std::shuffle(texels.begin(), texels.end(), rng);
  texels.resize(std::min<size_t>(texels.size(), std::max(1, options.max_texels)));
  return texels;
}

double FractionWithin(const std::vector<double>& errors, double tolerance) {
  if (errors.empty()) return std::nan("");
  const auto within = std::count_if(errors.begin(), errors.end(), [&](double e) { return e <= tolerance; });
  return static_cast<double>(within) / errors.size();
}

nlohmann::json NumberOrNull(double value) { return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr); }

}  // namespace

void RequireSameSize(const fit::Material& material, const std::string& material_folder, const simulate::Truth& truth) {
  if (material.width == truth.width() && material.height == truth.height()) return;
  common::ThrowInvalidInput(material_folder, "is " + std::to_string(material.width) + "x" + std::to_string(material.height) +
                                         " texels but the truth is " + std::to_string(truth.width()) + "x" +
                                         std::to_string(truth.height()),
                    "compare a material fitted at the truth's resolution");
}

CompareMetrics Compare(const fit::Material& material, const simulate::Truth& truth, const CompareOptions& options) {
  RequireSameSize(material, options.material_folder, truth);
  CompareMetrics metrics;
  metrics.material_folder = options.material_folder;
  metrics.truth_folder = truth.folder().string();
  metrics.truth_kind = truth.kind();
  metrics.btdf = fit::MaterialModelName(material.model);
  metrics.truth_has_parameters = truth.parameters() != nullptr;
  const simulate::RigTruth& rig = truth.rig();
  const std::vector<bool> held_out = HeldOutDots(material, options, rig.dots.size(), metrics);
  const std::vector<int> texels = TexelSubset(material, options);
  metrics.texels_compared = texels.size();

  const fit::MaterialEvaluator evaluator(material);
  const model::Hemicube grid(material.ndf_resolution);
  const model::Vec3 camera = rig.pose.Centre();
  // The single-interface baseline has no alpha; its NDF (the GGX lobe of its one rough
  // refraction) still compares.
  const bool fitted_alpha = material.model == fit::MaterialModel::kDualMicrofacet;
  std::vector<double> alpha_errors, ndf_errors, rho_d_errors;
  RelativeRmse heldout, all_dots;
  common::ProgressBar progress("compare", static_cast<int64_t>(texels.size()), "texels");
  for (int t : texels) {
    const int x = t % material.width, y = t / material.width;
    const fit::TexelBtdf fitted = evaluator.Texel(x, y);
    if (const simulate::MaterialTruth* parameters = truth.parameters()) {
      if (fitted_alpha) alpha_errors.push_back(std::abs(fitted.params().alpha - parameters->Params(x, y).alpha));
      ndf_errors.push_back(fit::NdfRelativeL2(grid, fitted.ndf(), *parameters->TexelNdf(x, y)));
    }
    const double true_rho_d = model::Luminance(truth.RhoD(x, y));
    if (true_rho_d > 1e-3) rho_d_errors.push_back(std::abs(model::Luminance(fitted.params().rho_d) / true_rho_d - 1.0));
    const model::Vec3 position = rig.sample.TexelCentre(x, y);
    const model::Vec3 o = (camera - position).normalized();
    for (size_t q = 0; q < rig.dots.size(); ++q) {
      const model::Vec3 i = (rig.dots[q].position - position).normalized();
      const double fitted_value = model::Luminance(fitted.Evaluate(i, o)), expected = model::Luminance(truth.Evaluate(x, y, i, o));
      all_dots.Add(fitted_value, expected);
      if (held_out[q]) heldout.Add(fitted_value, expected);
    }
    progress.Advance();
  }
  progress.Finish();
  metrics.alpha_within_0_05 = FractionWithin(alpha_errors, 0.05);
  metrics.alpha_error_median = common::Median(alpha_errors);
  metrics.ndf_rel_l2_median = common::Median(ndf_errors);
  metrics.rho_d_rel_error_median = common::Median(rho_d_errors);
  metrics.heldout_rel_rmse = heldout.Value();
  metrics.all_dots_rel_rmse = all_dots.Value();
  return metrics;
}

nlohmann::json ToJson(const CompareMetrics& metrics) {
  return {
      {"material", metrics.material_folder},
      {"truth", metrics.truth_folder},
      {"truth_kind", metrics.truth_kind},
      {"btdf", metrics.btdf},
      {"texels_compared", metrics.texels_compared},
      {"alpha_within_0_05", NumberOrNull(metrics.alpha_within_0_05)},
      {"alpha_error_median", NumberOrNull(metrics.alpha_error_median)},
      {"ndf_rel_l2_median", NumberOrNull(metrics.ndf_rel_l2_median)},
      {"rho_d_rel_error_median", NumberOrNull(metrics.rho_d_rel_error_median)},
      {"heldout_rel_rmse", NumberOrNull(metrics.heldout_rel_rmse)},
      {"all_dots_rel_rmse", NumberOrNull(metrics.all_dots_rel_rmse)},
      {"heldout_dots", metrics.heldout_dots},
      {"holdout_recorded", metrics.holdout_recorded},
  };
}

}  // namespace svbtdf::report
