// svbtdf run SESSION --out MATERIAL: calibrate, process and fit in one go. Every step resumes:
// an existing SESSION/calibration.json is used as is, an unfinished processing continues where it
// stopped, and the fit continues from its checkpoint.

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "fit_command.h"
#include "quality_output.h"
#include "svbtdf/calib/calibrate_session.h"
#include "svbtdf/common/error.h"
#include "svbtdf/session/session.h"
#include "svbtdf/process/process_session.h"
#include "svbtdf/fit/slice_store.h"
#include "svbtdf/process/calibration_quality.h"

namespace svbtdf::cli {
namespace {
namespace fs = std::filesystem;

struct RunOptions {
  std::string session, out, work;
  std::string representatives = "0.01";
  process::ProcessOptions process;
  fit::FitMaterialOptions fit;
  bool strict = false;
};

calib::SessionCalibration CalibrationOf(const session::Session& session) {
  const fs::path path = session.folder() / "calibration.json";
  if (fs::exists(path)) {
    std::printf("== 1/3 calibration: using %s\n", path.c_str());
    return calib::ReadSessionCalibration(path);
  }
  std::printf("== 1/3 calibrating %s\n", session.folder().c_str());
  const calib::SessionCalibration calibration = calib::CalibrateSession(session);
  calib::WriteSessionCalibration(path, calibration);
  std::printf("camera fx %.1f fy %.1f, RMS %.3f px; sample plane RMS %.3f px; monitor %.2f mm behind, dots RMS %.3f mm\n",
              calibration.camera.camera.fx, calibration.camera.camera.fy, calibration.camera.rms_px,
              calibration.sample_plane.rms_px, 1000 * calibration.monitor.distance_m, calibration.monitor.residual_rms_mm);
  return calibration;
}

void ProcessUnlessDone(const session::Session& session, const calib::SessionCalibration& calibration, const fs::path& processed,
                       const process::ProcessOptions& options) {
  try {
    fit::SliceStore::Open(processed);
    std::printf("== 2/3 processing: using %s\n", processed.c_str());
    return;
  } catch (const Error&) {
    // Not there or unfinished: process (an unfinished store resumes).
  }
  std::printf("== 2/3 processing into %s\n", processed.c_str());
  const process::ProcessReport report = process::ProcessSession(session, calibration, processed, options);
  std::printf("%d dots (%d resumed), %lld of %lld texels valid, %.1f s\n", report.dots, report.dots_resumed,
              static_cast<long long>(report.valid_texels), static_cast<long long>(report.texels), report.seconds);
}

void Run(const RunOptions& options) {
  const fs::path out = options.out;
  if (fs::exists(out) && (!fs::is_directory(out) || !fs::is_empty(out))) {
    ThrowInvalidInput(out.string(), "exists and is not empty; a material is never overwritten", "choose a new --out folder");
  }
  const fs::path work = options.work.empty() ? fs::path(out.string() + ".work") : fs::path(options.work);
  const session::Session session = session::Session::Open(options.session);
  const session::SessionVerification verification = session.Verify(/*check_crc=*/false);
  if (!verification.complete()) {
    ThrowInvalidInput(options.session, "is not a complete session: " + verification.Summary(),
                      "finish the capture (re-run 'svbtdf acquire' with the same --out) or check it with 'svbtdf session verify'");
  }
  // Every stage's output is checked after it (docs/quality.md), also when an earlier run made it.
  const calib::SessionCalibration calibration = CalibrationOf(session);
  std::vector<fit::QualityWarning> warnings =
      process::CheckCalibration(calibration, (session.folder() / "calibration.json").string());
  PrintQualityWarnings(warnings);
  ProcessUnlessDone(session, calibration, work / "processed", options.process);
  const std::vector<fit::QualityWarning> processed = fit::CheckSliceStore(work / "processed");
  PrintQualityWarnings(processed);
  warnings.insert(warnings.end(), processed.begin(), processed.end());
  std::printf("== 3/3 fitting\n");
  fit::FitMaterialOptions fit_options = options.fit;
  fit_options.representative_fraction = ParseRepresentatives(options.representatives);
  warnings = FitAndWriteMaterial(work / "processed", out, fit_options, &warnings);
  std::printf("intermediate files (calibrated slices, reusable): %s\n", work.c_str());
  if (warnings.empty()) {
    std::printf("quality: no warnings (%s)\n", (out / "quality.json").c_str());
  } else {
    std::fflush(stdout);
    std::fprintf(stderr, "svbtdf: %zu quality warning%s, recorded in %s: the material may be badly wrong\n",
                 warnings.size(), warnings.size() == 1 ? "" : "s", (out / "quality.json").c_str());
  }
  ExitIfStrict(warnings, options.strict);
}

}  // namespace

void AddRunCommand(CLI::App& app) {
  auto options = std::make_shared<RunOptions>();
  CLI::App* run = app.add_subcommand("run", "Calibrate, process and fit a capture session in one go (resumable)");
  run->add_option("session", options->session, "capture session folder")->required();
  run->add_option("--out", options->out, "new material folder")->required();
  run->add_option("--work", options->work, "folder for the processed slices (default: MATERIAL.work)");
  run->add_option("--light-resolution", options->process.light_resolution, "light hemicube of the resampled slices")
      ->capture_default_str();
  AddFitOptions(run, &options->fit, &options->representatives);
  AddStrictFlag(run, &options->strict);
  run->callback([options] {
    options->process.threads = options->fit.threads;
    Run(*options);
  });
}

}  // namespace svbtdf::cli
