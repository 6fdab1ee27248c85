// svbtdf run SESSION --out MATERIAL: calibrate, process and fit in one go (process::RunPipeline).
// Every step resumes: an existing SESSION/calibration.json is used as is, an unfinished processing
// continues where it stopped, and the fit continues from its checkpoint.

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "commands.h"
#include "svbtdf/common/folder_lock.h"
#include "fit_command.h"
#include "quality_output.h"
#include "svbtdf/calib/emission_profile.h"
#include "svbtdf/process/pipeline.h"

namespace svbtdf::cli {
namespace {
namespace fs = std::filesystem;

struct RunOptions {
  std::string session, out, work, emission_profile, polarisation;
  std::string representatives = "0.01";
  process::PipelineOptions pipeline;
  bool strict = false;
};

void Run(RunOptions options) {
  process::PipelineOptions& pipeline = options.pipeline;
  pipeline.session = options.session;
  pipeline.out = options.out;
  pipeline.work = options.work;
  if (!options.emission_profile.empty()) {
    pipeline.process.emission = calib::ReadEmissionProfileFile(options.emission_profile);
  }
  if (!options.polarisation.empty()) pipeline.process.polarisation = options.polarisation;
  pipeline.fit.representative_fraction = fit::ParseRepresentativeFraction(options.representatives);
  // The material names the run; its work folder is only ever written under it.
  const common::FolderLock lock = common::FolderLock::Acquire(pipeline.out, "svbtdf run");
  const process::PipelineOutcome outcome = process::RunPipeline(pipeline, ConsoleListener());
  std::printf("intermediate files (calibrated slices, reusable): %s\n", outcome.work.c_str());
  const fs::path quality = pipeline.out / "quality.json";
  if (outcome.warnings.empty()) {
    std::printf("quality: no warnings (%s)\n", quality.c_str());
  } else {
    std::fflush(stdout);
    std::fprintf(stderr, "svbtdf: %zu quality warning%s, recorded in %s: the material may be badly wrong\n",
                 outcome.warnings.size(), outcome.warnings.size() == 1 ? "" : "s", quality.c_str());
  }
  ExitIfStrict(outcome.warnings, options.strict);
}

}  // namespace

void AddRunCommand(CLI::App& app) {
  auto options = std::make_shared<RunOptions>();
  CLI::App* run = app.add_subcommand("run", "Calibrate, process and fit a capture session in one go (resumable)");
  run->add_option("session", options->session, "capture session folder")->required();
  run->add_option("--out", options->out, "new material folder")->required();
  run->add_option("--work", options->work, "folder for the processed slices (default: MATERIAL.work)");
  run->add_option("--light-resolution", options->pipeline.process.light_resolution, "light hemicube of the resampled slices")
      ->capture_default_str();
  run->add_option("--emission-profile", options->emission_profile,
                  "the monitor's measured emission profile (svbtdf calibrate-emission) instead of the calibration's");
  run->add_option("--monitor-polarisation,--monitor-polarization", options->polarisation,
                  "none or linear:DEG instead of the session's rig.monitor.polarisation: a polarised screen's samples "
                  "are corrected for the slab's polarised Fresnel (docs/capture.md, 'A polarised monitor')");
  AddFitOptions(run, &options->pipeline.fit, &options->representatives);
  AddStrictFlag(run, &options->strict);
  run->callback([options] {
    options->pipeline.process.threads = options->pipeline.fit.threads;
    Run(*options);
  });
}

}  // namespace svbtdf::cli
