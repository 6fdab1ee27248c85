// svbtdf calibrate-emission DIFFUSER_SESSION --out PROFILE.json: the monitor's angular emission
// profile, measured with a Lambertian diffuser in the sample holder (process/emission_calibration.h).

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "commands.h"
#include "svbtdf/calib/emission_profile.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/folder_lock.h"
#include "svbtdf/process/emission_calibration.h"

namespace svbtdf::cli {
namespace {
namespace fs = std::filesystem;

struct CalibrateEmissionOptions {
  std::string session, out, work, texels = "16x16";
  process::EmissionCalibrationOptions calibration;
};

void ParseGrid(const std::string& text, process::EmissionCalibrationOptions* options) {
  const GridSize texels = ParseGridSize(text, "--texels", 256);
  options->texels_x = texels.cols;
  options->texels_y = texels.rows;
}

void PrintProfile(const calib::EmissionFit& fit) {
  const calib::EmissionProfile& p = fit.profile;
  const calib::EmissionFitReport& r = fit.report;
  std::printf("emission profile from %lld samples of %lld texels: covered %.0f-%.0f degrees, residual %.2f%% RMS\n",
              static_cast<long long>(r.observations), static_cast<long long>(r.texels), p.covered_min_deg,
              p.covered_max_deg, 100.0 * r.residual_rms);
  std::printf("best single cos^n: n = %.2f (residual %.2f%% RMS%s)\n", p.exponent, 100.0 * r.cos_power_residual_rms,
              r.cos_power_residual_rms > 1.5 * r.residual_rms + 0.002 ? ": the table fits better" : "");
  std::printf("  theta (deg)   P       +- (1 sigma)\n");
  for (size_t k = 0; k < p.table.size(); k += 5) {
    std::printf("  %5.1f        %.4f  %.2f%%\n", k * p.step_deg, p.table[k], 100.0 * r.table_std[k]);
  }
}

void Run(CalibrateEmissionOptions options) {
  ParseGrid(options.texels, &options.calibration);
  if (!(options.calibration.fit.step_deg >= 0.5 && options.calibration.fit.step_deg <= 10.0)) {
    common::ThrowInvalidInput("--step", "must be from 0.5 to 10 degrees");
  }
  const fs::path out = options.out;
  const fs::path work = options.work.empty() ? fs::path(out.string() + ".work") : fs::path(options.work);
  const common::FolderLock lock = common::FolderLock::Acquire(work, "svbtdf calibrate-emission");
  const process::EmissionCalibration result = process::CalibrateEmission(options.session, work, options.calibration);
  PrintProfile(result.fit);
  calib::WriteEmissionProfileFile(out, result.fit.profile, result.fit.report, result.provenance);
  std::printf("profile: %s (use it with 'svbtdf process|run SESSION --emission-profile %s')\n", out.c_str(),
              out.c_str());
  std::printf("processed diffuser (reusable): %s\n", work.c_str());
}

}  // namespace

void AddCalibrateEmissionCommand(CLI::App& app) {
  auto options = std::make_shared<CalibrateEmissionOptions>();
  CLI::App* command = app.add_subcommand(
      "calibrate-emission",
      "Measure the monitor's angular emission profile from a session of a Lambertian diffuser (docs/capture.md)");
  command->add_option("session", options->session, "capture session of the diffuser (calibrated, or calibrated now)")
      ->required();
  command->add_option("--out", options->out, "the profile file to write (PROFILE.json)")->required();
  command->add_option("--work", options->work, "folder for the processed diffuser (default: PROFILE.json.work)");
  command->add_option("--texels", options->texels, "processing grid WIDTHxHEIGHT over the diffuser")
      ->capture_default_str();
  command->add_option("--step", options->calibration.fit.step_deg, "node spacing of the tabulated profile (degrees)")
      ->capture_default_str();
  command->add_option("--threads", options->calibration.threads, "worker threads (0: all cores)")->capture_default_str();
  command->callback([options] { Run(*options); });
}

}  // namespace svbtdf::cli
