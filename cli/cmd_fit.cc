// svbtdf fit PROCESSED --out MATERIAL: the dual-microfacet material of a processed session.

#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "svbtdf/common/folder_lock.h"
#include "fit_command.h"
#include "quality_output.h"
#include "svbtdf/common/error.h"
#include "svbtdf/process/pipeline.h"

namespace svbtdf::cli {
namespace {

struct FitCommandOptions {
  std::string processed, out;
  std::string representatives = "0.01";
  fit::FitMaterialOptions fit;
  bool strict = false;
};

}  // namespace

void AddFitOptions(CLI::App* command, fit::FitMaterialOptions* options, std::string* representatives) {
  const std::map<std::string, fit::MaterialModel> models = {{"dual", fit::MaterialModel::kDualMicrofacet},
                                                            {"ggx", fit::MaterialModel::kWalterGgx},
                                                            {"slab", fit::MaterialModel::kSlab}};
  command->add_option("--model", options->model,
                      "dual (the dual-microfacet model), ggx (the single-interface baseline) or slab (two rough "
                      "interfaces, each side's GGX roughness fitted; docs/fitting.md)")
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
  command->add_flag("!--no-uncertainty", options->uncertainty,
                    "do not compute the per-texel standard errors (a material of format version 1, as before)");
  command->add_flag("!--no-model-error", options->standard_errors.model_error,
                    "leave the model error (from each texel's two fits) out of the standard errors, to measure what "
                    "it adds (docs/fitting.md, \"Uncertainty\")");
  command->add_option("--model-error-pool", options->standard_errors.model_error_pool_radius,
                      "radius in texels over which the model error's draws are averaged (1: the 3 x 3 window; 0: each "
                      "texel's own)")
      ->capture_default_str();
  command->add_flag("!--fixed-horizon", options->free_horizon,
                    "hold the NDF at its horizon to the paper's 1e-6 instead of leaving it to the smoothness "
                    "prior (which fits rough lobes, GGX roughness above about 0.3, far better)");
  command->add_flag("--secant-alternations", options->secant_alternations,
                    "let alpha's alternations reach their fixed point by secant steps instead of stopping short "
                    "of it towards their start (better alpha, error bars and held-out error on the presets; off "
                    "by default until its effect on --internal-reflection is understood; docs/fitting.md)");
  command->add_flag("--internal-reflection", options->internal_reflection,
                    "add the light reflected once by each interface inside the slab to the model, fitted and "
                    "written with the material (format version 4; needs --fixed-horizon; about 0.4 ms more per "
                    "sample and pass, docs/fitting.md)");
  command->add_flag("--anisotropic-sides", options->slab_anisotropic,
                    "--model slab: try each interface's anisotropy too (GGX alpha_x, alpha_y and azimuth; kept where "
                    "it lowers the error by 10%; several times the fit's time; docs/fitting.md)");
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
    const common::FolderLock lock = common::FolderLock::Acquire(options->out, "svbtdf fit");
    fit::FitMaterialOptions fit_options = options->fit;
    fit_options.representative_fraction = fit::ParseRepresentativeFraction(options->representatives);
    ExitIfStrict(process::FitAndWriteMaterial(options->processed, options->out, fit_options, ConsoleListener()),
                 options->strict);
  });
}

}  // namespace svbtdf::cli
