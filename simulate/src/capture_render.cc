#include "svbtdf/simulate/capture_render.h"

#include <cmath>
#include <nlohmann/json.hpp>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/session/fiducials.h"
#include "svbtdf/common/error.h"

namespace svbtdf {
namespace fs = std::filesystem;
namespace {

bool Close(double a, double b) { return std::abs(a - b) <= 1e-9 * std::max(std::abs(a), std::abs(b)); }

double EtaOfTruthMaterial(const fs::path& manifest_path) {
  try {
    return nlohmann::json::parse(ReadTextFile(manifest_path)).at("eta").get<double>();
  } catch (const nlohmann::json::exception& e) {
    ThrowFormatError(manifest_path.string(), std::string("is malformed: ") + e.what());
  }
}

// The rebuilt rig must be the recorded one: a preset changed since the simulation ran would
// otherwise render different images under the same keys.
void RequireSameRig(const SimulatedSetup& setup, const RigTruth& truth, const fs::path& rig_path) {
  const CameraIntrinsics& k = setup.rig->config().intrinsics;
  const auto mismatch = [&](const std::string& what) {
    ThrowFormatError(rig_path.string(), "does not match preset '" + setup.preset.name + "' of this build (" + what + ")",
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

void RenderCaptureRadiance(const RigRenderer& renderer, const CaptureTruth& plan, const CaptureId& id,
                           FloatImage* radiance) {
  using session::CaptureKind;
  const CameraIntrinsics& k = renderer.rig().config().intrinsics;
  switch (id.key.kind) {
    case CaptureKind::kDark:
      *radiance = FloatImage(k.width, k.height, 3);
      return;
    case CaptureKind::kBoardView:
      renderer.RenderZhangBoard(plan.zhang_boards.at(id.key.view), radiance);
      return;
    case CaptureKind::kSamplePlaneView:
      renderer.RenderHolderBoard(plan.holder_board, radiance);
      return;
    case CaptureKind::kAllDots:
      renderer.RenderAllDots(radiance);
      return;
    case CaptureKind::kFiducials: {
      const DotGridConfig& grid = renderer.rig().config().dots;
      renderer.RenderDotSet(session::FiducialDots(grid.cols, grid.rows), radiance);
      return;
    }
    case CaptureKind::kFlatWhite:
      renderer.RenderFlatField(1.0, radiance);
      return;
    case CaptureKind::kDot:
      renderer.RenderDot(renderer.rig().dots().at(id.key.dot), radiance);
      return;
    case CaptureKind::kMonitorPoseView:
      break;
  }
  ThrowInvalidInput("capture", "the simulator does not render " + id.key.Format());
}

Vec2 CaptureWindowOrigin(const Rig& rig, const CaptureId& id) {
  // Board views are whole-sensor images; every other capture is the window.
  if (id.key.kind != session::CaptureKind::kBoardView) return Vec2::Zero();
  const SensorWindow& window = rig.config().window;
  return -Vec2(window.offset_x, window.offset_y);
}

std::unique_ptr<SimulatedSetup> MakeSimulatedSetup(SimulationPreset preset, uint64_t seed, int threads) {
  auto setup = std::make_unique<SimulatedSetup>();
  setup->preset = std::move(preset);
  setup->seed = seed;
  const SimulationPreset& p = setup->preset;
  setup->rig = std::make_unique<Rig>(p.rig);
  setup->material = std::make_unique<TruthMaterial>(
      TruthMaterial::FromPattern(p.pattern, p.rig.sample.texels_x, p.rig.sample.texels_y, p.eta, seed));
  setup->renderer = std::make_unique<RigRenderer>(*setup->rig, setup->material.get(), threads);
  setup->plan = PlanCapture(p, *setup->renderer, seed);
  return setup;
}

std::unique_ptr<SimulatedSetup> LoadSimulatedSetup(const fs::path& out, int threads) {
  const fs::path rig_path = out / "truth" / "rig.json";
  if (!fs::exists(rig_path)) {
    ThrowInvalidInput(out.string(), "is not the output folder of `svbtdf simulate` (no truth/rig.json)",
                      "run `svbtdf simulate --preset tiny --out " + out.string() + "` first");
  }
  const RigTruth truth = ReadRigTruth(rig_path);
  if (truth.capture.truth_kind != "model") {
    ThrowInvalidInput(rig_path.string(), "holds a '" + truth.capture.truth_kind + "' truth; only 'model' can be re-rendered");
  }
  SimulationPreset preset = MakePreset(truth.capture.preset);
  preset.eta = EtaOfTruthMaterial(out / "truth" / "material.json");
  // The screen as it was simulated (svbtdf simulate may have turned, tilted or mirrored it).
  preset.rig.monitor.orientation_deg = truth.monitor.orientation_deg;
  preset.rig.monitor.tilt_deg = truth.monitor.tilt_deg;
  preset.rig.monitor.mirrored = truth.monitor.mirrored;
  std::unique_ptr<SimulatedSetup> setup = MakeSimulatedSetup(std::move(preset), truth.capture.seed, threads);
  setup->plan.truth_kind = truth.capture.truth_kind;
  RequireSameRig(*setup, truth, rig_path);
  return setup;
}

}  // namespace svbtdf
