// svbtdf process SESSION --out DIR: a calibrated session to the slice store (docs/slice-store.md).

#include <array>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "svbtdf/common/folder_lock.h"
#include "quality_output.h"
#include "svbtdf/calib/emission_profile.h"
#include "svbtdf/common/error.h"
#include "svbtdf/process/pipeline.h"

namespace svbtdf::cli {
namespace {

struct ProcessCommandOptions {
  std::string session, out;
  std::string texels;  // "WxH"
  std::string emission_profile, polarisation;
  process::ProcessOptions process;
  bool strict = false;
};

void ParseTexels(const std::string& text, process::ProcessOptions* options) {
  if (text.empty()) return;
  const GridSize texels = ParseGridSize(text, "--texels", 100000);
  options->texels_x = texels.cols;
  options->texels_y = texels.rows;
}

void RunProcess(ProcessCommandOptions options) {
  ParseTexels(options.texels, &options.process);
  if (!options.emission_profile.empty()) options.process.emission = calib::ReadEmissionProfileFile(options.emission_profile);
  if (!options.polarisation.empty()) options.process.polarisation = options.polarisation;
  const common::FolderLock lock = common::FolderLock::Acquire(options.out, "svbtdf process");
  const process::ProcessStage stage = process::ProcessAndCheck(options.session, options.out, options.process);
  const process::ProcessReport& report = stage.report;
  if (report.already_complete) {
    std::printf("already complete: %d dots, %lld of %lld texels valid; nothing to do\n", report.dots,
                static_cast<long long>(report.valid_texels), static_cast<long long>(report.texels));
  } else {
    std::printf("processed %d dots (%d resumed) from %lld images in %.1f s: %lld of %lld texels valid\n", report.dots,
                report.dots_resumed, static_cast<long long>(report.images_read), report.seconds,
                static_cast<long long>(report.valid_texels), static_cast<long long>(report.texels));
  }
  std::printf("slice store: %s\n", options.out.c_str());
  const std::array<double, 3>& flat = report.white_exitance_noise;
  std::printf("flat white noise per texel: %.2f%% / %.2f%% / %.2f%% (R / G / B), in the error bars of k_s and rho_d\n",
              100 * flat[0], 100 * flat[1], 100 * flat[2]);
  PrintQualityWarnings(stage.warnings);
  ExitIfStrict(stage.warnings, options.strict);
}

}  // namespace

void AddProcessCommand(CLI::App& app) {
  auto options = std::make_shared<ProcessCommandOptions>();
  CLI::App* process = app.add_subcommand("process", "Turn a calibrated session into per-texel BTDF samples (slice store)");
  process->add_option("session", options->session, "capture session folder (calibrated)")->required();
  process->add_option("--out", options->out, "output folder (new, or an unfinished processing to resume)")->required();
  process->add_option("--texels", options->texels, "texel grid WIDTHxHEIGHT (default: the session's, else ~2 px per texel)");
  process->add_option("--light-resolution", options->process.light_resolution,
                      "light hemicube resolution of the resampled slices (power of two)")
      ->capture_default_str();
  process->add_option("--emission-profile", options->emission_profile,
                      "the monitor's measured emission profile (svbtdf calibrate-emission) instead of the calibration's");
  process->add_option("--monitor-polarisation,--monitor-polarization", options->polarisation,
                      "none or linear:DEG instead of the session's rig.monitor.polarisation: a polarised screen's "
                      "samples are corrected for the slab's polarised Fresnel (docs/capture.md, 'A polarised monitor')");
  process->add_option("--threads", options->process.threads, "worker threads (0: all cores)")->capture_default_str();
  AddStrictFlag(process, &options->strict);
  process->callback([options] { RunProcess(*options); });
}

}  // namespace svbtdf::cli
