// svbtdf validate-model: the dual-microfacet model against the Monte Carlo slab, reproducing the
// paper's Figs. 3 and 5 (docs/validation.md). Prints a table of relative L2 errors; --json writes
// them, --plots writes plane-of-incidence cross-sections and an HTML page showing them (the
// table, the JSON and the page are built by report/validation_page.h).

#include <spdlog/spdlog.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/progress.h"
#include "svbtdf/model/ndf_factory.h"
#include "svbtdf/report/validation_page.h"
#include "svbtdf/simulate/model_validation.h"

namespace svbtdf::cli {
namespace {

namespace fs = std::filesystem;

struct ValidateModelOptions {
  std::string ndf = "beckmann";
  double roughness = 0.3;
  double eta = 1.5;
  int64_t samples = 4000000;
  uint64_t seed = 1;
  int threads = 0;
  int resolution = 32;
  int max_bounces = 100;
  std::vector<double> incidences = {30.0, 45.0, 60.0};
  std::string json;
  std::string plots;
};

// Checks and creates the output locations before the (minute-long) run, so that a bad path fails
// at once instead of after the work.
void PrepareOutputs(const ValidateModelOptions& options) {
  std::error_code error;
  if (!options.json.empty()) {
    if (fs::exists(options.json)) {
      common::ThrowInvalidInput(options.json, "already exists", "validate-model never overwrites; choose another --json file");
    }
    const fs::path parent = fs::path(options.json).parent_path();
    if (!parent.empty()) fs::create_directories(parent, error);
    if (error) common::ThrowIoError(parent.string(), "cannot create: " + error.message());
  }
  if (!options.plots.empty()) {
    if (fs::exists(options.plots) && (!fs::is_directory(options.plots) || !fs::is_empty(options.plots))) {
      common::ThrowInvalidInput(options.plots, "exists and is not an empty folder",
                        "validate-model never overwrites; choose a new --plots folder");
    }
    fs::create_directories(options.plots, error);
    if (error) common::ThrowIoError(options.plots, "cannot create: " + error.message());
  }
}

void CheckOptions(const ValidateModelOptions& options) {
  if (!(options.roughness > 0) || !std::isfinite(options.roughness)) {
    common::ThrowInvalidInput("--roughness", "must be finite and > 0");
  }
  if (options.samples < 1000) common::ThrowInvalidInput("--samples", "must be at least 1000 paths per case");
  if (options.resolution < 4 || options.resolution % 2 != 0) {
    common::ThrowInvalidInput("--resolution", "must be an even number >= 4", "the paper uses 32");
  }
  if (options.threads < 0) common::ThrowInvalidInput("--threads", "must be >= 0 (0: all cores)");
  if (options.max_bounces < 2) common::ThrowInvalidInput("--max-bounces", "must be >= 2 to cross the slab");
}

// The settings recorded in the JSON and on the page.
report::ValidationSettings Settings(const ValidateModelOptions& options) {
  return {.ndf = options.ndf,
          .roughness = options.roughness,
          .eta = options.eta,
          .samples = options.samples,
          .seed = options.seed,
          .resolution = options.resolution,
          .max_bounces = options.max_bounces};
}

void RunValidateModel(const ValidateModelOptions& options) {
  CheckOptions(options);
  PrepareOutputs(options);
  simulate::ValidationOptions validation;
  validation.make_ndf = [&](double roughness) {
    model::AnalyticNdfParams params;
    params.alpha_x = roughness;
    params.alpha_y = roughness;
    return model::MakeAnalyticNdf(options.ndf, params);
  };
  validation.make_ndf(options.roughness);  // fails early on an unknown --ndf
  validation.roughness = options.roughness;
  validation.eta = options.eta;
  validation.incidences_deg = options.incidences;
  validation.slice.paths = options.samples;
  validation.slice.seed = options.seed;
  validation.slice.threads = options.threads;
  validation.slice.max_interactions = options.max_bounces;

  const model::Hemicube grid(options.resolution);
  common::ProgressBar progress("validate-model",
                       static_cast<int64_t>(validation.configurations.size() * options.incidences.size()),
                       "cases");
  const std::vector<simulate::ValidationCase> cases =
      simulate::ValidateModel(validation, grid, [&](const simulate::ValidationCase&) { progress.Advance(); });
  progress.Finish();
  std::fputs(report::ValidationTable(cases).c_str(), stdout);

  if (!options.json.empty()) {
    common::WriteTextAtomically(options.json, report::ValidationJson(cases, Settings(options)).dump(2) + "\n",
                        /*overwrite=*/false);
    spdlog::info("wrote {}", options.json);
  }
  if (!options.plots.empty()) {
    fs::create_directories(options.plots);
    report::WriteValidationPage(cases, Settings(options), grid, options.plots);
    spdlog::info("wrote {} plots and {}", cases.size(), (fs::path(options.plots) / "index.html").string());
  }
}

}  // namespace

void AddValidateModelCommand(CLI::App& app) {
  auto options = std::make_shared<ValidateModelOptions>();
  CLI::App* cmd = app.add_subcommand(
      "validate-model",
      "Compare the dual-microfacet model with a Monte Carlo slab (the paper's Figs. 3 and 5)");
  cmd->add_option("--ndf", options->ndf, "NDF of both interfaces and of the models: beckmann, ggx, ...")
      ->capture_default_str();
  cmd->add_option("--roughness", options->roughness, "NDF roughness of each rough interface")
      ->capture_default_str();
  cmd->add_option("--eta", options->eta, "relative index of refraction n_slab / n_air (> 1)")
      ->capture_default_str();
  cmd->add_option("--samples", options->samples, "Monte Carlo paths per case")->capture_default_str();
  cmd->add_option("--seed", options->seed, "random seed (results are identical for any --threads)")
      ->capture_default_str();
  cmd->add_option("--threads", options->threads, "worker threads, 0 = all cores")->capture_default_str();
  cmd->add_option("--resolution", options->resolution, "hemicube top-face resolution (cells per side)")
      ->capture_default_str();
  cmd->add_option("--max-bounces", options->max_bounces, "interface hits before a path counts as capped")
      ->capture_default_str();
  cmd->add_option("--incidence", options->incidences, "view angles in degrees")->capture_default_str();
  cmd->add_option("--json", options->json, "write the errors to this JSON file (never overwritten)");
  cmd->add_option("--plots", options->plots, "write PNG cross-sections and index.html to this new folder");
  cmd->callback([options] { RunValidateModel(*options); });
}

}  // namespace svbtdf::cli
