#pragma once
// A simulated lab made ready for its capture: the preset with the command's overrides, the ground
// truth written to OUT/truth (docs/truth-format.md) and the rig, material, renderer and exposures
// of SimulatedSetup. The capture itself is `svbtdf acquire`'s loop run with the simulated camera
// and display (acquire/simulated_session.h).

#include <cstdint>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <string>

#include "svbtdf/simulate/capture_render.h"
#include "svbtdf/simulate/presets.h"

namespace svbtdf::simulate {

struct SimulationOptions {
  std::string preset = "tiny";
  uint64_t seed = 1;
  double eta = 0.0;          // > 0 overrides the preset's eta
  std::string truth = "model";  // model | montecarlo
  int threads = 0;
  bool progress = true;
  bool noise = true;  // false: no shot or read noise (quantisation stays), for accuracy checks
  // The screen's pose (MonitorConfig) instead of the preset's; NaN: the preset's.
  double monitor_orientation_deg = std::numeric_limits<double>::quiet_NaN();
  double monitor_tilt_deg = std::numeric_limits<double>::quiet_NaN();
  bool mirror_monitor = false;  // a mirrored display, which calibration must refuse (tests)
  // The dot grid's columns and rows instead of the preset's (`--dots 20x20`), laid over the same
  // span of the screen: the same rig captured more or less densely (bench/scaling.py); 0: the
  // preset's.
  int dot_cols = 0, dot_rows = 0;
  // The screen's angular emission instead of the preset's (`--monitor-emission lcd:5`), and the
  // material pattern instead of the preset's (`--pattern diffuser`): together the diffuser
  // session and the sample session of one LCD rig (docs/simulator.md, "An LCD rig").
  std::optional<EmissionProfile> monitor_emission;
  // The screen's polarisation instead of the preset's unpolarised light
  // (`--monitor-polarization linear:45`; docs/simulator.md, "A polarised LCD"); analytic truth only.
  std::optional<Polarisation> monitor_polarisation;
  std::string pattern;
  // A lab's own rig (`svbtdf simulate --rig`, simulate/rig_file.h) instead of the preset's; the
  // preset still gives the material. `rig_source` names it in the session's notes.
  std::optional<RigConfig> rig;
  std::string rig_source;
};

// The preset named by `options` with its overrides applied; svbtdf::Error(kInvalidInput) naming
// the option for an unknown preset or truth, or an eta <= 1.
SimulationPreset PresetWithOptions(const SimulationOptions& options);

// Builds the simulated lab of `options` and writes its truth into `truth_folder` (material.json
// and its maps, rig.json), or, when the folder holds it already (a resumed simulation), reads the
// Monte Carlo truth back instead of tracing it again: resumed images are then byte-identical.
// Never overwrites a truth file.
std::unique_ptr<SimulatedSetup> PrepareSimulation(const std::filesystem::path& truth_folder,
                                                  const SimulationOptions& options);

// Rebuilds the setup of the simulation in OUT (the folder `svbtdf simulate --out OUT` wrote) from
// OUT/truth/rig.json (preset, seed, monitor pose, exposures, board poses) and OUT/truth/material.json
// (eta; a Monte Carlo truth is read back), and checks that the rebuilt rig and plan equal the
// recorded ones. Throws svbtdf::Error naming the file when OUT is not a simulation or does not
// match what this build would simulate.
std::unique_ptr<SimulatedSetup> LoadSimulatedSetup(const std::filesystem::path& out, int threads);

}  // namespace svbtdf::simulate
