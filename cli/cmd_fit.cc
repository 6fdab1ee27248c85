// svbtdf fit PROCESSED --out MATERIAL: the dual-microfacet material of a processed session.

#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "fit_command.h"
#include "quality_output.h"
#include "svbtdf/common/error.h"
#include "svbtdf/fit/fit_material.h"
#include "svbtdf/fit/material.h"
#include "svbtdf/fit/slice_store.h"
#include "svbtdf/fit/slice_store_format.h"
#include "svbtdf/process/calibration_quality.h"

namespace svbtdf::cli {
namespace {
namespace fs = std::filesystem;

struct FitCommandOptions {
  std::string processed, out;
  std::string representatives = "0.01";
  fit::FitMaterialOptions fit;
  bool strict = false;
};

}  // namespace

namespace {

// The checkpoint of an unfinished fit of MATERIAL, next to it (the material folder itself is
// written only once, complete).
fs::path FitCheckpointPath(const fs::path& material) {
  return material.parent_path() / (material.filename().string() + ".partial-fits.jsonl");
}

}  // namespace

double ParseRepresentatives(const std::string& text) {
  if (text == "all") return 1.0;
  try {
    size_t used = 0;
    const double fraction = std::stod(text, &used);
    if (used == text.size() && fraction > 0 && fraction <= 1) return fraction;
  } catch (const std::exception&) {
  }
  ThrowInvalidInput("--representatives", "must be a fraction in (0, 1] or 'all', got '" + text + "'");
}

std::vector<fit::QualityWarning> FitAndWriteMaterial(const fs::path& processed, const fs::path& out,
                                                     fit::FitMaterialOptions options,
                                                     const std::vector<fit::QualityWarning>* earlier) {
  if (fs::exists(out) && (!fs::is_directory(out) || !fs::is_empty(out))) {
    ThrowInvalidInput(out.string(), "exists and is not empty; a material is never overwritten", "choose a new --out folder");
  }
  const fit::SliceStore store = fit::SliceStore::Open(processed);
  options.checkpoint = FitCheckpointPath(out);
  const fit::Material material = fit::FitMaterial(store, options);
  fit::WriteMaterial(out, material);
  fs::remove(options.checkpoint);
  const nlohmann::json& statistics = material.provenance["statistics"];
  std::printf("fitted %s: %s representatives of %s valid texels (%s failed, %s resumed) in %.1f s (%.2f s per fit); "
              "median residual %.3f\n",
              fit::MaterialModelName(material.model), statistics["representatives"].dump().c_str(),
              statistics["valid_texels"].dump().c_str(), statistics["failed_fits"].dump().c_str(),
              statistics["resumed_fits"].dump().c_str(), statistics["seconds"].get<double>(),
              statistics["seconds_per_fit"].get<double>(),
              statistics["median_relative_rmse"].is_number() ? statistics["median_relative_rmse"].get<double>() : -1.0);
  if (statistics["refined_representatives"].get<int64_t>() > 0) {
    std::printf("refined alpha and k_s of %s representatives\n", statistics["refined_representatives"].dump().c_str());
  }
  if (statistics["refined_texels"].get<int64_t>() > 0) {
    std::printf("refined alpha, k_s and weights of %s interpolated texels: median residual %.3f -> %.3f\n",
                statistics["refined_texels"].dump().c_str(), statistics["median_relative_rmse_blended"].get<double>(),
                statistics["median_relative_rmse_refined"].get<double>());
  }
  std::printf("material: %s\n", out.c_str());

  std::vector<fit::QualityWarning> warnings;
  if (earlier) {
    warnings = *earlier;
  } else {
    const fs::path calibration = processed / fit::store::kCalibration;
    warnings = process::CheckCalibration(calib::ReadSessionCalibration(calibration), calibration.string());
    const std::vector<fit::QualityWarning> stored = fit::CheckSliceStore(processed);
    warnings.insert(warnings.end(), stored.begin(), stored.end());
    PrintQualityWarnings(warnings);
  }
  const std::vector<fit::QualityWarning> fitted = fit::CheckMaterial(material, out);
  PrintQualityWarnings(fitted);
  warnings.insert(warnings.end(), fitted.begin(), fitted.end());
  fit::WriteQuality(out, warnings);
  return warnings;
}

void AddFitOptions(CLI::App* command, fit::FitMaterialOptions* options, std::string* representatives) {
  const std::map<std::string, fit::MaterialModel> models = {{"dual", fit::MaterialModel::kDualMicrofacet},
                                                            {"ggx", fit::MaterialModel::kWalterGgx}};
  command->add_option("--model", options->model, "dual (the dual-microfacet model) or ggx (the single-interface baseline)")
      ->transform(CLI::CheckedTransformer(models))
      ->default_str("dual");
  command->add_option("--eta", options->eta, "relative index of refraction (default: the session's)");
  command->add_option("--representatives", *representatives, "fraction of texels fitted (k-means representatives), or 'all'")
      ->capture_default_str();
  command->add_option("--holdout", options->holdout, "fraction of the dots withheld from the fit, for 'svbtdf compare'")
      ->capture_default_str();
  command->add_flag("!--no-refine", options->refine_texels,
                    "keep the paper's plain interpolation and alpha criterion instead of fitting every texel's "
                    "alpha, k_s and weights to its own samples");
  command->add_flag("!--fixed-horizon", options->free_horizon,
                    "hold the NDF at its horizon to the paper's 1e-6 instead of leaving it to the smoothness "
                    "prior (which fits rough lobes, GGX roughness above about 0.3, far better)");
  command->add_option("--ndf-resolution", options->ndf_resolution, "NDF hemicube resolution (top face)")
      ->capture_default_str();
  command->add_option("--seed", options->seed, "seed of the clustering and the held-out dots")->capture_default_str();
  command->add_option("--threads", options->threads, "worker threads (0: all cores)")->capture_default_str();
}

void AddFitCommand(CLI::App& app) {
  auto options = std::make_shared<FitCommandOptions>();
  CLI::App* fit = app.add_subcommand("fit", "Fit the dual-microfacet material to a processed session");
  fit->add_option("processed", options->processed, "output folder of 'svbtdf process'")->required();
  fit->add_option("--out", options->out, "new material folder")->required();
  AddFitOptions(fit, &options->fit, &options->representatives);
  AddStrictFlag(fit, &options->strict);
  fit->callback([options] {
    fit::FitMaterialOptions fit_options = options->fit;
    fit_options.representative_fraction = ParseRepresentatives(options->representatives);
    ExitIfStrict(FitAndWriteMaterial(options->processed, options->out, fit_options), options->strict);
  });
}

}  // namespace svbtdf::cli
