// svbtdf simulate: a synthetic capture session of a known material, for tests and demos.

#include <cstdio>
#include <memory>
#include <optional>
#include <string>

#include "commands.h"
#include "svbtdf/common/folder_lock.h"
#include "svbtdf/common/error.h"
#include "svbtdf/simulate/presets.h"
#include "svbtdf/simulate/rig_file.h"
#include "svbtdf/acquire/simulated_session.h"

namespace svbtdf::cli {

void AddSimulateCommand(CLI::App& app) {
  auto options = std::make_shared<simulate::SimulationOptions>();
  auto out = std::make_shared<std::string>();
  auto plan_file = std::make_shared<std::string>();
  auto rig_file = std::make_shared<std::string>();
  std::string presets;
  for (const std::string& name : simulate::PresetNames()) presets += (presets.empty() ? "" : ", ") + name;
  CLI::App* simulate = app.add_subcommand(
      "simulate", "Render a synthetic capture session (OUT/session) of a known material (OUT/truth)");
  CLI::Option* preset = simulate->add_option("--preset", options->preset, "rig and material preset: " + presets);
  simulate->add_option("--plan", *plan_file,
                       "capture plan file (docs/capture.md): simulate that capture (its dots, exposures, repeats and "
                       "calibration captures) instead of the preset's");
  simulate->add_option("--rig", *rig_file,
                       "rig file (docs/capture.md): simulate on this rig instead of the preset's (its preset gives the "
                       "material)");
  simulate->add_option("--out", *out, "output folder (new, or an unfinished simulation to resume)")->required();
  simulate->add_option("--seed", options->seed, "seed of the material pattern and the noise")->capture_default_str();
  simulate->add_option("--eta", options->eta, "override the preset's relative index of refraction (> 1)");
  simulate->add_option("--truth", options->truth, "model: a dual-microfacet material; montecarlo: traced two-interface slab materials")
      ->check(CLI::IsMember({"model", "montecarlo"}))
      ->capture_default_str();
  simulate->add_flag("!--no-noise", options->noise, "no shot or read noise (quantisation stays): for accuracy checks");
  simulate->add_option("--monitor-orientation", options->monitor_orientation_deg,
                       "turn the screen about its normal (degrees, counter-clockwise seen from the sample; 0: its "
                       "top edge toward +y) instead of the preset's");
  simulate->add_option("--monitor-tilt", options->monitor_tilt_deg, "tilt the screen about the x axis (degrees) instead of the preset's");
  simulate->add_flag("--mirror-monitor", options->mirror_monitor,
                     "show a mirror image of the screen (a mirrored display mode), which calibration must refuse");
  auto dots = std::make_shared<std::string>();
  simulate->add_option("--dots", *dots,
                       "the dot grid COLSxROWS instead of the preset's, over the same span of the screen (the same "
                       "rig captured more or less densely)");
  auto emission = std::make_shared<std::string>();
  simulate->add_option("--monitor-emission", *emission,
                       "the screen's angular emission instead of the preset's: isotropic, lambertian or lcd:N (cos^N); "
                       "docs/simulator.md, 'An LCD rig'");
  auto polarisation = std::make_shared<std::string>();
  simulate->add_option("--monitor-polarization,--monitor-polarisation", *polarisation,
                       "the screen's polarisation: none (default) or linear:DEG, the field's angle from the screen's "
                       "pixel x axis toward its top (an LCD; docs/simulator.md, 'A polarised LCD')");
  simulate->add_option("--pattern", options->pattern,
                       "the material instead of the preset's: smooth, grid-sheet, leaf-glass, rice-paper, or diffuser (a "
                       "Lambertian transmitter, for `svbtdf calibrate-emission`)");
  simulate->add_option("--threads", options->threads, "worker threads (0: all cores)")->capture_default_str();
  simulate->callback([options, out, plan_file, rig_file, preset, dots, emission, polarisation] {
    if (!dots->empty()) {
      if (!plan_file->empty()) {
        common::ThrowInvalidInput("--dots", "and --plan both give the dots", "leave one out: a plan lists its own dots");
      }
      const GridSize grid = ParseGridSize(*dots, "--dots", 1000);
      options->dot_cols = grid.cols;
      options->dot_rows = grid.rows;
    }
    if (!emission->empty()) options->monitor_emission = simulate::EmissionProfile::Parse(*emission, "--monitor-emission");
    if (!polarisation->empty()) {
      options->monitor_polarisation = simulate::Polarisation::Parse(*polarisation, "--monitor-polarization");
    }
    if (!rig_file->empty()) {
      const simulate::RigFile rig = simulate::ReadRigFile(*rig_file);
      if (preset->count() > 0 && options->preset != rig.preset) {
        common::ThrowInvalidInput("--preset", "is '" + options->preset + "' but " + *rig_file + " starts from preset '" +
                                                  rig.preset + "'",
                                  "leave --preset out: the rig file names the preset whose material is simulated");
      }
      options->preset = rig.preset;
      options->rig = rig.rig;
      options->rig_source = *rig_file;
      if (options->eta == 0.0) options->eta = rig.eta;
    } else if (preset->count() == 0) {
      common::ThrowInvalidInput("simulate", "needs --preset NAME or --rig FILE");
    }
    std::optional<acquire::CapturePlan> plan;
    if (!plan_file->empty()) plan = acquire::ReadCapturePlan(*plan_file);
    const common::FolderLock lock = common::FolderLock::Acquire(*out, "svbtdf simulate");
    const acquire::SimulationOutput result = acquire::SimulateSession(*out, *options, plan ? &*plan : nullptr);
    if (result.already_complete) {
      std::printf("already complete: %lld images of preset '%s'; nothing to do\n  session: %s\n  truth:   %s\n",
                  static_cast<long long>(result.images), options->preset.c_str(), result.session.c_str(),
                  result.truth.c_str());
      return;
    }
    std::printf("simulated %lld images (%lld resumed) of preset '%s'\n  session: %s\n  truth:   %s\n",
                static_cast<long long>(result.images), static_cast<long long>(result.resumed),
                options->preset.c_str(), result.session.c_str(), result.truth.c_str());
  });
}

}  // namespace svbtdf::cli
