#include "svbtdf/report/compare.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "svbtdf/common/error.h"
#include "svbtdf/common/json.h"
#include "svbtdf/common/progress.h"
#include "svbtdf/common/statistics.h"
#include "svbtdf/fit/ndf_error.h"
#include "svbtdf/simulate/montecarlo_truth.h"

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
    dots = common::IntegerArrayAt<int>(provenance["holdout"], "dots", "the material's provenance");
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

// Counts how often |fitted - truth| <= 2 se over the events whose se is known (se >= 0).
// Also keeps |fitted - truth| / se, whose median is 0.674 for calibrated normal errors.
struct Coverage {
  int64_t within = 0, count = 0;
  std::vector<double> z;
  void Add(double fitted, double truth, double se) {
    if (!(se >= 0) || !std::isfinite(fitted) || !std::isfinite(truth)) return;
    ++count;
    within += std::abs(fitted - truth) <= 2.0 * se;
    z.push_back(se > 0 ? std::abs(fitted - truth) / se : (fitted == truth ? 0.0 : 1e30));
  }
  double Value() const { return count > 0 ? static_cast<double>(within) / count : std::nan(""); }
  double MedianZ() const { return common::Median(z); }
};

std::vector<double> Ranks(const std::vector<double>& v) {
  std::vector<size_t> order(v.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return v[a] < v[b]; });
  std::vector<double> ranks(v.size());
  for (size_t i = 0; i < order.size();) {
    size_t j = i;
    while (j + 1 < order.size() && v[order[j + 1]] == v[order[i]]) ++j;
    for (size_t k = i; k <= j; ++k) ranks[order[k]] = 0.5 * (i + j);
    i = j + 1;
  }
  return ranks;
}

}  // namespace

double SpearmanCorrelation(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size() || a.size() < 3) return std::nan("");
  const std::vector<double> ra = Ranks(a), rb = Ranks(b);
  const double n = static_cast<double>(a.size());
  double ma = 0, mb = 0;
  for (size_t i = 0; i < ra.size(); ++i) ma += ra[i] / n, mb += rb[i] / n;
  double sab = 0, saa = 0, sbb = 0;
  for (size_t i = 0; i < ra.size(); ++i) {
    sab += (ra[i] - ma) * (rb[i] - mb);
    saa += (ra[i] - ma) * (ra[i] - ma);
    sbb += (rb[i] - mb) * (rb[i] - mb);
  }
  return saa > 0 && sbb > 0 ? sab / std::sqrt(saa * sbb) : std::nan("");
}

void RequireSameSize(const fit::Material& material, const std::string& material_folder, const simulate::Truth& truth) {
  if (material.width == truth.width() && material.height == truth.height()) return;
  common::ThrowInvalidInput(material_folder, "is " + std::to_string(material.width) + "x" + std::to_string(material.height) +
                                         " texels but the truth is " + std::to_string(truth.width()) + "x" +
                                         std::to_string(truth.height()),
                    "compare a material fitted at the truth's resolution");
}

namespace {

// The true roughness sqrt(alpha_x alpha_y) of a slab interface and its two axes (long first), or
// NaN where it is not a GGX lobe about the normal (the fit's family).
std::array<double, 3> TrueGgxSide(const simulate::SlabInterfaceSpec& spec) {
  const model::AnalyticNdfParams& p = spec.params;
  if (spec.ndf != "ggx" || p.theta_x != 0 || p.theta_y != 0) return {std::nan(""), std::nan(""), std::nan("")};
  return {std::sqrt(p.alpha_x * p.alpha_y), std::max(p.alpha_x, p.alpha_y), std::min(p.alpha_x, p.alpha_y)};
}

// The medians of one side's fitted roughness, axes and standard error over some texels.
struct SideMedians {
  std::vector<double> roughness, alpha_x, alpha_y, se;
  void Add(const fit::SlabSide& side, double standard_error) {
    roughness.push_back(side.Roughness());
    alpha_x.push_back(side.alpha_x);
    alpha_y.push_back(side.alpha_y);
    se.push_back(standard_error);
  }
  // The fraction of the texels whose roughness is within 15% of `truth` (NaN without one).
  double Within15(double truth) const {
    if (!std::isfinite(truth)) return std::nan("");
    std::vector<double> errors;
    for (double v : roughness) errors.push_back(std::abs(v / truth - 1.0));
    return FractionWithin(errors, 0.15);
  }
};

// Each true slab material's texels among `texels`, their fitted interfaces against the truth's.
std::vector<CompareMetrics::SlabRecovery> SlabRecoveries(const fit::Material& material, const simulate::MonteCarloTruth& truth,
                                                         const std::vector<int>& texels) {
  std::vector<CompareMetrics::SlabRecovery> recoveries;
  for (size_t m = 0; m < truth.materials().size(); ++m) {
    const simulate::SlabMaterial& slab = truth.materials()[m];
    CompareMetrics::SlabRecovery r;
    r.label = slab.label;
    const std::array<double, 3> true_entry = TrueGgxSide(slab.entry), true_exit = TrueGgxSide(slab.exit);
    r.true_entry = true_entry[0];
    r.true_exit = true_exit[0];
    r.true_entry_axes = {true_entry[1], true_entry[2]};
    r.true_exit_axes = {true_exit[1], true_exit[2]};
    SideMedians entry, exit;
    for (int t : texels) {
      if (truth.material_of(t) != static_cast<int>(m)) continue;
      const int x = t % material.width, y = t / material.width;
      const fit::SlabInterfaces fitted = fit::TexelSlab(material, x, y);
      entry.Add(fitted.entry, material.slab_entry_roughness_se.at(x, y));
      exit.Add(fitted.exit, material.slab_exit_roughness_se.at(x, y));
    }
    r.texels = entry.roughness.size();
    if (entry.roughness.empty()) continue;
    r.entry_within_15 = entry.Within15(r.true_entry);
    r.exit_within_15 = exit.Within15(r.true_exit);
    r.entry_median = common::Median(entry.roughness);
    r.exit_median = common::Median(exit.roughness);
    r.entry_axes_median = {common::Median(entry.alpha_x), common::Median(entry.alpha_y)};
    r.exit_axes_median = {common::Median(exit.alpha_x), common::Median(exit.alpha_y)};
    r.entry_se_median = common::Median(entry.se);
    r.exit_se_median = common::Median(exit.se);
    recoveries.push_back(r);
  }
  return recoveries;
}

}  // namespace

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
  const bool uncertainty = material.has_uncertainty();
  Coverage alpha_coverage, k_s_coverage, rho_d_coverage, shadowing_coverage, width_coverage;
  std::vector<double> predicted_error, residual_error, actual_error;
  const simulate::MonteCarloTruth* slabs = truth.montecarlo();
  std::vector<RelativeRmse> heldout_by_slab(slabs ? slabs->materials().size() : 0);
  std::vector<size_t> texels_by_slab(heldout_by_slab.size(), 0);
  common::ProgressBar progress("compare", static_cast<int64_t>(texels.size()), "texels");
  for (int t : texels) {
    const int x = t % material.width, y = t / material.width;
    const fit::TexelBtdf fitted = evaluator.Texel(x, y);
    if (const simulate::MaterialTruth* parameters = truth.parameters()) {
      if (fitted_alpha) alpha_errors.push_back(std::abs(fitted.params().alpha - parameters->Params(x, y).alpha));
      ndf_errors.push_back(fit::NdfRelativeL2(grid, fitted.ndf(), *parameters->TexelNdf(x, y)));
      if (uncertainty) {
        const model::DualMicrofacetParams true_params = parameters->Params(x, y);
        alpha_coverage.Add(fitted.params().alpha, true_params.alpha, material.alpha_se.at(x, y));
        for (int c = 0; c < 3; ++c) k_s_coverage.Add(material.k_s.at(x, y, c), true_params.k_s[c], material.k_s_se.at(x, y, c));
        shadowing_coverage.Add(material.shadowing_roughness.at(x, y), parameters->shadowing_roughness.at(x, y),
                               material.shadowing_roughness_se.at(x, y));
        width_coverage.Add(material.ndf_width.at(x, y), fit::NdfWidth(grid, *parameters->TexelNdf(x, y)),
                           material.ndf_width_se.at(x, y));
      }
    }
    if (uncertainty) {
      const model::Rgb true_rho_d = truth.RhoD(x, y);
      for (int c = 0; c < 3; ++c) rho_d_coverage.Add(material.rho_d.at(x, y, c), true_rho_d[c], material.rho_d_se.at(x, y, c));
    }
    RelativeRmse texel_heldout;
    const double true_rho_d = model::Luminance(truth.RhoD(x, y));
    if (true_rho_d > 1e-3) rho_d_errors.push_back(std::abs(model::Luminance(fitted.params().rho_d) / true_rho_d - 1.0));
    const model::Vec3 position = rig.sample.TexelCentre(x, y);
    const model::Vec3 o = (camera - position).normalized();
    for (size_t q = 0; q < rig.dots.size(); ++q) {
      const model::Vec3 i = (rig.dots[q].position - position).normalized();
      const double fitted_value = model::Luminance(fitted.Evaluate(i, o)), expected = model::Luminance(truth.Evaluate(x, y, i, o));
      all_dots.Add(fitted_value, expected);
      if (held_out[q]) heldout.Add(fitted_value, expected), texel_heldout.Add(fitted_value, expected);
      if (held_out[q] && slabs) heldout_by_slab[slabs->material_of(t)].Add(fitted_value, expected);
    }
    if (slabs) ++texels_by_slab[slabs->material_of(t)];
    if (uncertainty && material.prediction_se.at(x, y) >= 0 && material.residual.at(x, y) >= 0 &&
        std::isfinite(texel_heldout.Value())) {
      predicted_error.push_back(material.prediction_se.at(x, y));
      residual_error.push_back(material.residual.at(x, y));
      actual_error.push_back(texel_heldout.Value());
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
  metrics.z_median = {alpha_coverage.MedianZ(), k_s_coverage.MedianZ(), rho_d_coverage.MedianZ(),
                      shadowing_coverage.MedianZ(), width_coverage.MedianZ()};
  metrics.coverage_alpha = alpha_coverage.Value();
  metrics.coverage_k_s = k_s_coverage.Value();
  metrics.coverage_rho_d = rho_d_coverage.Value();
  metrics.coverage_shadowing = shadowing_coverage.Value();
  metrics.coverage_ndf_width = width_coverage.Value();
  metrics.heldout_rank_correlation = SpearmanCorrelation(predicted_error, actual_error);
  metrics.residual_rank_correlation = SpearmanCorrelation(residual_error, actual_error);
  for (size_t m = 0; m < heldout_by_slab.size(); ++m) {
    metrics.heldout_by_truth_slab.push_back({slabs->materials()[m].label, texels_by_slab[m], heldout_by_slab[m].Value()});
  }
  if (material.model == fit::MaterialModel::kSlab && truth.montecarlo()) {
    metrics.slab_recovery = SlabRecoveries(material, *truth.montecarlo(), texels);
  }
  return metrics;
}

namespace {

nlohmann::json HeldOutBySlabToJson(const std::vector<CompareMetrics::TruthSlabError>& errors) {
  nlohmann::json list = nlohmann::json::array();
  for (const CompareMetrics::TruthSlabError& e : errors) {
    list.push_back({{"label", e.label}, {"texels", e.texels}, {"heldout_rel_rmse", NumberOrNull(e.heldout_rel_rmse)}});
  }
  return list;
}

nlohmann::json SlabRecoveriesToJson(const std::vector<CompareMetrics::SlabRecovery>& recoveries) {
  nlohmann::json list = nlohmann::json::array();
  for (const CompareMetrics::SlabRecovery& r : recoveries) {
    list.push_back({{"label", r.label},
                    {"texels", r.texels},
                    {"true_entry_roughness", NumberOrNull(r.true_entry)},
                    {"true_exit_roughness", NumberOrNull(r.true_exit)},
                    {"entry_roughness_median", NumberOrNull(r.entry_median)},
                    {"exit_roughness_median", NumberOrNull(r.exit_median)},
                    {"entry_roughness_se_median", NumberOrNull(r.entry_se_median)},
                    {"exit_roughness_se_median", NumberOrNull(r.exit_se_median)},
                    {"entry_within_15_percent", NumberOrNull(r.entry_within_15)},
                    {"exit_within_15_percent", NumberOrNull(r.exit_within_15)},
                    {"true_entry_axes", {NumberOrNull(r.true_entry_axes[0]), NumberOrNull(r.true_entry_axes[1])}},
                    {"true_exit_axes", {NumberOrNull(r.true_exit_axes[0]), NumberOrNull(r.true_exit_axes[1])}},
                    {"entry_axes_median", {NumberOrNull(r.entry_axes_median[0]), NumberOrNull(r.entry_axes_median[1])}},
                    {"exit_axes_median", {NumberOrNull(r.exit_axes_median[0]), NumberOrNull(r.exit_axes_median[1])}}});
  }
  return list;
}

}  // namespace

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
      {"coverage_2se",
       {{"alpha", NumberOrNull(metrics.coverage_alpha)},
        {"k_s", NumberOrNull(metrics.coverage_k_s)},
        {"rho_d", NumberOrNull(metrics.coverage_rho_d)},
        {"shadowing_roughness", NumberOrNull(metrics.coverage_shadowing)},
        {"ndf_width", NumberOrNull(metrics.coverage_ndf_width)}}},
      {"error_over_se_median",
       {{"alpha", NumberOrNull(metrics.z_median[0])},
        {"k_s", NumberOrNull(metrics.z_median[1])},
        {"rho_d", NumberOrNull(metrics.z_median[2])},
        {"shadowing_roughness", NumberOrNull(metrics.z_median[3])},
        {"ndf_width", NumberOrNull(metrics.z_median[4])}}},
      {"heldout_rank_correlation", NumberOrNull(metrics.heldout_rank_correlation)},
      {"residual_rank_correlation", NumberOrNull(metrics.residual_rank_correlation)},
      {"slab_recovery", SlabRecoveriesToJson(metrics.slab_recovery)},
      {"heldout_by_truth_slab", HeldOutBySlabToJson(metrics.heldout_by_truth_slab)},
  };
}

}  // namespace svbtdf::report
