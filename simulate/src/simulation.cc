#include "svbtdf/simulate/simulation.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/json.h"
#include "svbtdf/common/error.h"
#include "svbtdf/simulate/montecarlo_truth.h"
#include "svbtdf/simulate/truth_io.h"
#include "svbtdf/simulate/truth_material.h"

namespace svbtdf::simulate {
namespace fs = std::filesystem;
namespace {

// The truth the renderer shows the camera. The analytic material is cheap to regenerate; the
// Monte Carlo one is traced once, written to OUT/truth at once (so that an interrupted capture
// keeps it), and read back when a simulation is resumed: the file's float values are exactly the
// ones the first run rendered, so resumed images are byte-identical.
std::unique_ptr<SpatialBtdf> MakeTruth(const SimulationPreset& preset, const Rig& rig, const SimulationOptions& options,
                                       const fs::path& truth_folder) {
  const SampleConfig& sample = preset.rig.sample;
  if (options.truth == "model") {
    auto material = std::make_unique<TruthMaterial>(
        TruthMaterial::FromPattern(preset.pattern, sample.texels_x, sample.texels_y, preset.eta, options.seed));
    if (!fs::exists(truth_folder / "material.json")) WriteMaterialTruth(truth_folder, *material);
    return material;
  }
  if (fs::exists(truth_folder / "material.json")) {
    auto truth = std::make_unique<MonteCarloTruth>(ReadMonteCarloTruth(truth_folder));
    if (truth->texels_x() != sample.texels_x || truth->texels_y() != sample.texels_y || truth->eta() != preset.eta ||
        truth->seed != options.seed) {
      common::ThrowInvalidInput(truth_folder.string(), "holds the truth of other settings", "choose a new output folder");
    }
    return truth;
  }
  std::vector<SlabMaterial> materials = DefaultSlabMaterials();
  std::vector<int> index = SlabIndexMap(sample.texels_x, sample.texels_y, static_cast<int>(materials.size()), options.seed);
  const ViewGrid views = ViewGrid::Spanning(rig.camera().Centre(), sample, preset.view_nodes_per_axis);
  auto truth = std::make_unique<MonteCarloTruth>(MonteCarloTruth::Trace(sample.texels_x, sample.texels_y, preset.eta,
                                                                        std::move(materials), std::move(index), views,
                                                                        preset.montecarlo, options.seed,
                                                                        options.threads, options.progress));
  WriteMonteCarloTruth(truth_folder, *truth);
  return truth;
}

bool Close(double a, double b) { return std::abs(a - b) <= 1e-9 * std::max(std::abs(a), std::abs(b)); }

double EtaOfTruthMaterial(const fs::path& manifest_path) {
  try {
    return common::ReadJsonFile(manifest_path).at("eta").get<double>();
  } catch (const nlohmann::json::exception& e) {
    common::ThrowFormatError(manifest_path.string(), std::string("is malformed: ") + e.what());
  }
}

// The rebuilt rig must be the recorded one: a preset changed since the simulation ran would
// otherwise render different images under the same keys.
void RequireSameRig(const SimulatedSetup& setup, const RigTruth& truth, const fs::path& rig_path) {
  const CameraIntrinsics& k = setup.rig->config().intrinsics;
  const auto mismatch = [&](const std::string& what) {
    common::ThrowFormatError(rig_path.string(), "does not match preset '" + setup.preset.name + "' of this build (" + what + ")",
                     "re-run `svbtdf simulate` with this build");
  };
  if (k.width != truth.camera.width || k.height != truth.camera.height || !Close(k.fx, truth.camera.fx)) mismatch("camera");
  const std::vector<Dot>& dots = setup.rig->dots();
  if (dots.size() != truth.dots.size()) mismatch("number of dots");
  for (size_t q = 0; q < dots.size(); ++q) {
    if (dots[q].monitor_x != truth.dots[q].monitor_x || dots[q].monitor_y != truth.dots[q].monitor_y) mismatch("dot positions");
  }
  const std::vector<double>& a = setup.plan.dot_exposures_s;
  const std::vector<double>& b = truth.capture.dot_exposures_s;
  if (a.size() != b.size()) mismatch("exposure bracket");
  for (size_t e = 0; e < a.size(); ++e) {
    if (!Close(a[e], b[e])) mismatch("dot exposures");
  }
  if (setup.plan.zhang_boards.size() != truth.capture.zhang_boards.size()) mismatch("board views");
}

}  // namespace

SimulationPreset PresetWithOptions(const SimulationOptions& options) {
  if (options.truth != "model" && options.truth != "montecarlo") {
    common::ThrowInvalidInput("--truth", "must be model or montecarlo, got '" + options.truth + "'");
  }
  SimulationPreset preset = MakePreset(options.preset);
  if (options.rig) preset.rig = *options.rig;
  if (!options.noise) {
    preset.rig.sensor.shot_noise = false;
    preset.rig.sensor.read_noise = 0.0;
  }
  if (!std::isnan(options.monitor_orientation_deg)) preset.rig.monitor.orientation_deg = options.monitor_orientation_deg;
  if (!std::isnan(options.monitor_tilt_deg)) preset.rig.monitor.tilt_deg = options.monitor_tilt_deg;
  if (options.mirror_monitor) preset.rig.monitor.mirrored = true;
  if (options.dot_cols != 0 || options.dot_rows != 0) {
    if (options.dot_cols < 2 || options.dot_rows < 2 || options.dot_cols > 1000 || options.dot_rows > 1000) {
      common::ThrowInvalidInput("--dots", "needs 2 to 1000 columns and rows, got " + std::to_string(options.dot_cols) +
                                              "x" + std::to_string(options.dot_rows));
    }
    preset.rig.dots.cols = options.dot_cols;
    preset.rig.dots.rows = options.dot_rows;
  }
  if (options.monitor_emission) preset.rig.monitor.emission = *options.monitor_emission;
  if (options.monitor_polarisation) {
    if (options.monitor_polarisation->linear() && options.truth != "model") {
      common::ThrowInvalidInput("--monitor-polarization", "applies to the analytic truth only (--truth model)",
                                "the Monte Carlo slab tracer does not follow polarisation");
    }
    preset.rig.monitor.polarisation = *options.monitor_polarisation;
  }
  if (preset.rig.monitor.polarisation.linear() && options.truth != "model") {  // a rig file's
    common::ThrowInvalidInput("monitor.polarisation", "applies to the analytic truth only (--truth model)",
                              "the Monte Carlo slab tracer does not follow polarisation");
  }
  if (!options.pattern.empty()) {
    const std::vector<std::string> names = TruthPatternNames();
    if (std::find(names.begin(), names.end(), options.pattern) == names.end()) {
      common::ThrowInvalidInput("--pattern", "unknown material pattern '" + options.pattern + "'",
                                "use smooth, grid-sheet, leaf-glass, rice-paper or diffuser");
    }
    if (options.truth != "model") {
      common::ThrowInvalidInput("--pattern", "applies to the analytic truth only (--truth model)");
    }
    preset.pattern = options.pattern;
  }
  if (options.eta != 0.0) {
    if (!(options.eta > 1.0) || !std::isfinite(options.eta)) {
      common::ThrowInvalidInput("--eta", "must be > 1, got " + std::to_string(options.eta));
    }
    preset.eta = options.eta;
  }
  return preset;
}

std::unique_ptr<SimulatedSetup> PrepareSimulation(const fs::path& truth_folder, const SimulationOptions& options) {
  SimulationPreset preset = PresetWithOptions(options);
  std::error_code error;
  fs::create_directories(truth_folder, error);
  if (error) common::ThrowIoError(truth_folder.string(), "cannot create: " + error.message(), "is the folder writable?");
  const TruthMaker make_truth = [&](const Rig& rig) { return MakeTruth(preset, rig, options, truth_folder); };
  std::unique_ptr<SimulatedSetup> setup = MakeSimulatedSetup(preset, options.seed, options.threads, make_truth);
  setup->plan.truth_kind = options.truth;
  if (!fs::exists(truth_folder / "rig.json")) WriteRigTruth(truth_folder / "rig.json", *setup->rig, setup->plan);
  return setup;
}

std::unique_ptr<SimulatedSetup> LoadSimulatedSetup(const fs::path& out, int threads) {
  const fs::path rig_path = out / "truth" / "rig.json";
  if (!fs::exists(rig_path)) {
    common::ThrowInvalidInput(out.string(), "is not the output folder of `svbtdf simulate` (no truth/rig.json)",
                      "run `svbtdf simulate --preset tiny --out " + out.string() + "` first");
  }
  const RigTruth truth = ReadRigTruth(rig_path);
  SimulationPreset preset = MakePreset(truth.capture.preset);
  preset.eta = EtaOfTruthMaterial(out / "truth" / "material.json");
  // The screen as it was simulated (svbtdf simulate may have turned, tilted or mirrored it).
  preset.rig.monitor.orientation_deg = truth.monitor.orientation_deg;
  preset.rig.monitor.tilt_deg = truth.monitor.tilt_deg;
  preset.rig.monitor.mirrored = truth.monitor.mirrored;
  // The dot grid as it was simulated (`svbtdf simulate --dots` may have replaced the preset's).
  if (!truth.dots.empty()) preset.rig.dots.cols = preset.rig.dots.rows = 0;
  for (const Dot& dot : truth.dots) {
    preset.rig.dots.cols = std::max(preset.rig.dots.cols, dot.col + 1);
    preset.rig.dots.rows = std::max(preset.rig.dots.rows, dot.row + 1);
  }
  preset.rig.monitor.emission = truth.monitor.emission;
  preset.rig.monitor.polarisation = truth.monitor.polarisation;
  if (!truth.capture.pattern.empty()) preset.pattern = truth.capture.pattern;
  SimulationOptions options;  // what MakeTruth needs to read the truth back (it exists: eta was read)
  options.truth = truth.capture.truth_kind;
  options.seed = truth.capture.seed;
  options.threads = threads;
  const TruthMaker read_truth = [&](const Rig& rig) { return MakeTruth(preset, rig, options, out / "truth"); };
  std::unique_ptr<SimulatedSetup> setup = MakeSimulatedSetup(preset, truth.capture.seed, threads, read_truth);
  setup->plan.truth_kind = truth.capture.truth_kind;
  RequireSameRig(*setup, truth, rig_path);
  return setup;
}

}  // namespace svbtdf::simulate
