// svbtdf compare: a fitted material against the simulator's ground truth (issue 5's metrics,
// computed by report/compare.h); prints a summary and writes the metrics with --json.

#include <nlohmann/json.hpp>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "commands.h"
#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/fit/material.h"
#include "svbtdf/report/compare.h"
#include "svbtdf/simulate/truth.h"

namespace svbtdf::cli {
namespace {
namespace fs = std::filesystem;

struct CompareCommandOptions {
  std::string material, truth, json;
  report::CompareOptions compare;
};

void PrintSummary(const report::CompareMetrics& m) {
  const auto percent = [](double v) { return std::isfinite(v) ? std::to_string(std::lround(1000 * v) / 10.0).substr(0, 5) + "%" : std::string("-"); };
  if (m.truth_has_parameters) {
    // A parametric material (ggx, slab) has no alpha: "-", not "nan%".
    std::printf("compared %zu texels (%s): alpha within 0.05 on %s, NDF rel. L2 median %.3f, ", m.texels_compared,
                m.btdf.c_str(), percent(m.alpha_within_0_05).c_str(), m.ndf_rel_l2_median);
  } else {
    std::printf("compared %zu texels with a %s truth (no true alpha or NDF): ", m.texels_compared, m.truth_kind.c_str());
  }
  std::printf("held-out rel. RMSE %.4f, all-dots rel. RMSE %.4f%s\n", m.heldout_rel_rmse, m.all_dots_rel_rmse,
              m.holdout_recorded ? "" : " (no held-out dots recorded: all dots)");
  // A material with standard errors: how often the truth lies within 2 of them.
  if (std::isfinite(m.coverage_rho_d) || std::isfinite(m.coverage_alpha)) {
    std::printf("truth within 2 standard errors: alpha %s, k_s %s, rho_d %s, shadowing %s, NDF width %s; "
                "rank correlation of the predicted and the held-out error %.2f (of the residual %.2f)\n",
                percent(m.coverage_alpha).c_str(), percent(m.coverage_k_s).c_str(), percent(m.coverage_rho_d).c_str(),
                percent(m.coverage_shadowing).c_str(), percent(m.coverage_ndf_width).c_str(), m.heldout_rank_correlation,
                m.residual_rank_correlation);
  }
  // A Monte Carlo truth: the held-out error on each of its slab materials' texels.
  for (const report::CompareMetrics::TruthSlabError& e : m.heldout_by_truth_slab) {
    std::printf("held-out rel. RMSE on the true slab %s (%zu texels): %.4f\n", e.label.substr(0, e.label.find(':')).c_str(),
                e.texels, e.heldout_rel_rmse);
  }
  // A slab material: each true slab's interfaces against the fitted ones (medians over its texels).
  const auto roughness = [](double v) { return std::isfinite(v) ? std::to_string(v).substr(0, 5) : std::string("-"); };
  for (const report::CompareMetrics::SlabRecovery& r : m.slab_recovery) {
    const auto side = [&](double median, const std::array<double, 2>& axes, double truth, const std::array<double, 2>& true_axes,
                          double within, double se) {
      return roughness(median) + " (" + roughness(axes[0]) + " x " + roughness(axes[1]) + "; true " + roughness(truth) +
             (std::isfinite(true_axes[0]) ? " (" + roughness(true_axes[0]) + " x " + roughness(true_axes[1]) + ")" : "") +
             ", within 15% on " + percent(within) + ", se " + roughness(se) + ")";
    };
    std::printf("slab %s (%zu texels): entry %s, exit %s\n", r.label.substr(0, r.label.find(':')).c_str(), r.texels,
                side(r.entry_median, r.entry_axes_median, r.true_entry, r.true_entry_axes, r.entry_within_15, r.entry_se_median).c_str(),
                side(r.exit_median, r.exit_axes_median, r.true_exit, r.true_exit_axes, r.exit_within_15, r.exit_se_median).c_str());
  }
}

void RunCompare(CompareCommandOptions options) {
  if (!options.json.empty() && fs::exists(options.json)) {
    common::ThrowInvalidInput(options.json, "already exists", "compare never overwrites; choose another --json file");
  }
  const fit::Material material = fit::ReadMaterial(options.material);
  const simulate::Truth truth = simulate::ReadTruth(options.truth);
  options.compare.material_folder = options.material;
  const report::CompareMetrics metrics = report::Compare(material, truth, options.compare);
  PrintSummary(metrics);
  if (!options.json.empty()) {
    common::WriteTextAtomically(options.json, report::ToJson(metrics).dump(2) + "\n", /*overwrite=*/false);
  }
}

}  // namespace

void AddCompareCommand(CLI::App& app) {
  auto options = std::make_shared<CompareCommandOptions>();
  CLI::App* compare = app.add_subcommand("compare", "Compare a fitted material with a simulator ground truth");
  compare->add_option("material", options->material, "fitted material folder")->required();
  compare->add_option("truth", options->truth, "ground-truth folder written by 'svbtdf simulate' (OUT/truth)")->required();
  compare->add_option("--json", options->json, "write the metrics to this new JSON file");
  compare->add_option("--texels", options->compare.max_texels, "compare at most this many texels (random, seeded)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  compare->add_option("--seed", options->compare.seed, "seed of the texel subset")->capture_default_str();
  compare->callback([options] { RunCompare(*options); });
}

}  // namespace svbtdf::cli
