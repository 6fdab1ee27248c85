// svbtdf compare: a fitted material against the simulator's ground truth (issue 5's metrics).

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "commands.h"
#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/progress.h"
#include "svbtdf/common/statistics.h"
#include "svbtdf/fit/material.h"
#include "svbtdf/fit/ndf_error.h"
#include "svbtdf/simulate/montecarlo_truth.h"
#include "svbtdf/simulate/session_writer.h"
#include "svbtdf/simulate/truth_io.h"

namespace svbtdf::cli {
namespace {
namespace fs = std::filesystem;

struct CompareOptions {
  std::string material, truth, json;
  int max_texels = 1000;
  uint64_t seed = 1;
};

// The ground truth either kind of simulation wrote, evaluated through the renderer's SpatialBtdf:
// the analytic dual-microfacet material (with a true alpha and NDF per texel) or the Monte Carlo
// slab truth (a BTDF and rho_d only).
class CompareTruth {
 public:
  explicit CompareTruth(const fs::path& folder) : kind_(ReadTruthKind(folder)) {
    if (kind_ == "montecarlo") {
      auto truth = std::make_unique<MonteCarloTruth>(ReadMonteCarloTruth(folder));
      montecarlo_ = truth.get();
      btdf_ = std::move(truth);
    } else {
      analytic_.emplace(ReadMaterialTruth(folder));
      btdf_ = std::make_unique<TruthMaterial>(analytic_->ToTruthMaterial());
    }
  }
  const std::string& kind() const { return kind_; }
  bool has_parameters() const { return analytic_.has_value(); }
  int width() const { return btdf_->texels_x(); }
  int height() const { return btdf_->texels_y(); }
  const MaterialTruth& analytic() const { return *analytic_; }

  Rgb RhoD(int x, int y) const {
    return analytic_ ? analytic_->Params(x, y).rho_d : montecarlo_->rho_d(montecarlo_->Index(x, y));
  }
  Rgb Evaluate(int x, int y, const Vec3& i, const Vec3& o) const { return btdf_->Evaluate(btdf_->Index(x, y), i, o); }

 private:
  std::string kind_;
  std::optional<MaterialTruth> analytic_;
  const MonteCarloTruth* montecarlo_ = nullptr;
  std::unique_ptr<SpatialBtdf> btdf_;
};

// Sums of squared errors and of squared truths of the luminance over (texel, dot) pairs.
struct RelativeRmse {
  double error = 0, norm = 0;
  void Add(double fitted, double truth) {
    error += Square(fitted - truth);
    norm += Square(truth);
  }
  nlohmann::json Json() const { return norm > 0 ? nlohmann::json(std::sqrt(error / norm)) : nlohmann::json(nullptr); }
  double Value() const { return norm > 0 ? std::sqrt(error / norm) : std::nan(""); }
};

void RunCompare(const CompareOptions& options) {
  if (!options.json.empty() && fs::exists(options.json)) {
    ThrowInvalidInput(options.json, "already exists", "compare never overwrites; choose another --json file");
  }
  const fit::Material material = fit::ReadMaterial(options.material);
  const CompareTruth truth(options.truth);
  const RigTruth rig = ReadRigTruth(fs::path(options.truth) / "rig.json");
  if (material.width != truth.width() || material.height != truth.height()) {
    ThrowInvalidInput(options.material, "is " + std::to_string(material.width) + "x" + std::to_string(material.height) +
                                            " texels but the truth is " + std::to_string(truth.width()) + "x" +
                                            std::to_string(truth.height()),
                      "compare a material fitted at the truth's resolution");
  }
  // Held-out dots recorded by the fit, or every dot when the fit withheld none.
  std::vector<int> dots;
  bool holdout_recorded = false;
  if (material.provenance.contains("holdout") && material.provenance["holdout"].contains("dots")) {
    dots = material.provenance["holdout"]["dots"].get<std::vector<int>>();
    holdout_recorded = true;
  } else {
    for (size_t q = 0; q < rig.dots.size(); ++q) dots.push_back(static_cast<int>(q));
  }
  // A random subset of texels keeps large materials quick; the seed makes it repeatable.
  std::vector<int> texels(static_cast<size_t>(material.width) * material.height);
  for (size_t t = 0; t < texels.size(); ++t) texels[t] = static_cast<int>(t);
  std::mt19937_64 rng(options.seed);
  std::shuffle(texels.begin(), texels.end(), rng);
  texels.resize(std::min<size_t>(texels.size(), std::max(1, options.max_texels)));

  const fit::MaterialEvaluator evaluator(material);
  const Hemicube grid(material.ndf_resolution);
  const Vec3 camera = rig.pose.Centre();
  std::vector<double> alpha_errors, ndf_errors, rho_d_errors;
  RelativeRmse heldout, all_dots;
  std::vector<bool> held_out(rig.dots.size(), false);
  for (int q : dots) {
    if (q < 0 || q >= static_cast<int>(rig.dots.size())) {
      ThrowFormatError(options.material, "records held-out dot " + std::to_string(q) + ", which the rig does not have");
    }
    held_out[q] = true;
  }
  const bool fitted_alpha = material.model == fit::MaterialModel::kDualMicrofacet;
  ProgressBar progress("compare", static_cast<int64_t>(texels.size()), "texels");
  for (int t : texels) {
    const int x = t % material.width, y = t / material.width;
    const fit::TexelBtdf fitted = evaluator.Texel(x, y);
    if (truth.has_parameters()) {  // a Monte Carlo truth has no alpha and no NDF to compare with
      // The baseline has no alpha; its NDF (the GGX lobe of the one rough refraction) compares.
      if (fitted_alpha) alpha_errors.push_back(std::abs(fitted.params().alpha - truth.analytic().Params(x, y).alpha));
      ndf_errors.push_back(fit::NdfRelativeL2(grid, fitted.ndf(), *truth.analytic().TexelNdf(x, y)));
    }
    const double true_rho_d = Luminance(truth.RhoD(x, y));
    if (true_rho_d > 1e-3) rho_d_errors.push_back(std::abs(Luminance(fitted.params().rho_d) / true_rho_d - 1.0));
    const Vec3 position = rig.sample.TexelCentre(x, y);
    const Vec3 o = (camera - position).normalized();
    for (size_t q = 0; q < rig.dots.size(); ++q) {
      const Vec3 i = (rig.dots[q].position - position).normalized();
      const double fitted_value = Luminance(fitted.Evaluate(i, o)), expected = Luminance(truth.Evaluate(x, y, i, o));
      all_dots.Add(fitted_value, expected);
      if (held_out[q]) heldout.Add(fitted_value, expected);
    }
    progress.Advance();
  }
  progress.Finish();
  const double within =
      alpha_errors.empty() ? std::nan("")
                           : static_cast<double>(std::count_if(alpha_errors.begin(), alpha_errors.end(),
                                                               [](double e) { return e <= 0.05; })) /
                                 alpha_errors.size();
  const auto number_or_null = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  const nlohmann::json out = {
      {"material", options.material},
      {"truth", options.truth},
      {"truth_kind", truth.kind()},
      {"btdf", fit::MaterialModelName(material.model)},
      {"texels_compared", texels.size()},
      {"alpha_within_0_05", number_or_null(within)},
      {"alpha_error_median", number_or_null(Median(alpha_errors))},
      {"ndf_rel_l2_median", number_or_null(Median(ndf_errors))},
      {"rho_d_rel_error_median", number_or_null(Median(rho_d_errors))},
      {"heldout_rel_rmse", heldout.Json()},
      {"all_dots_rel_rmse", all_dots.Json()},
      {"heldout_dots", dots.size()},
      {"holdout_recorded", holdout_recorded},
  };
  if (truth.has_parameters()) {
    std::printf("compared %zu texels (%s): alpha within 0.05 on %.1f%%, NDF rel. L2 median %.3f, ", texels.size(),
                fit::MaterialModelName(material.model), 100 * within, Median(ndf_errors));
  } else {
    std::printf("compared %zu texels with a %s truth (no true alpha or NDF): ", texels.size(), truth.kind().c_str());
  }
  std::printf("held-out rel. RMSE %.4f, all-dots rel. RMSE %.4f%s\n", heldout.Value(), all_dots.Value(),
              holdout_recorded ? "" : " (no held-out dots recorded: all dots)");
  if (!options.json.empty()) WriteTextAtomically(options.json, out.dump(2) + "\n", /*overwrite=*/false);
}

}  // namespace

void AddCompareCommand(CLI::App& app) {
  auto options = std::make_shared<CompareOptions>();
  CLI::App* compare = app.add_subcommand("compare", "Compare a fitted material with a simulator ground truth");
  compare->add_option("material", options->material, "fitted material folder")->required();
  compare->add_option("truth", options->truth, "ground-truth folder written by 'svbtdf simulate' (OUT/truth)")->required();
  compare->add_option("--json", options->json, "write the metrics to this new JSON file");
  compare->add_option("--texels", options->max_texels, "compare at most this many texels (random, seeded)")
      ->capture_default_str();
  compare->add_option("--seed", options->seed, "seed of the texel subset")->capture_default_str();
  compare->callback([options] { RunCompare(*options); });
}

}  // namespace svbtdf::cli
