#include "svbtdf/simulate/capture_render.h"

#include <algorithm>
#include <cmath>
#include <functional>

#include "svbtdf/common/error.h"
#include "svbtdf/session/fiducials.h"
#include "svbtdf/simulate/truth_material.h"

namespace svbtdf::simulate {

uint64_t NoiseStream(std::string_view what, int index, int bracket) {
  const uint64_t name_hash = std::hash<std::string_view>{}(what);
  return name_hash * 0x9e3779b97f4a7c15ULL ^ (uint64_t(index) << 16) ^ uint64_t(bracket);
}

uint64_t CaptureId::Stream() const {
  using session::CaptureKind;
  switch (key.kind) {
    case CaptureKind::kDark: return NoiseStream("dark", key.repeat, key.bracket);
    case CaptureKind::kBoardView: return NoiseStream("board", key.view, 0);
    case CaptureKind::kSamplePlaneView: return NoiseStream("holder_board", key.view, 0);
    case CaptureKind::kMonitorPoseView: return NoiseStream("monitor_pose", key.view, 0);
    case CaptureKind::kAllDots: return NoiseStream("all_dots", 0, key.bracket);
    case CaptureKind::kFiducials: return NoiseStream("fiducials", 0, key.bracket);
    case CaptureKind::kFlatWhite: return NoiseStream("flat", 0, key.bracket);
    case CaptureKind::kDot: return NoiseStream("dots", key.dot, key.bracket);
  }
  return 0;
}

std::string SceneOf(const session::CaptureKey& key) {
  session::CaptureKey scene = key;
  scene.bracket = scene.repeat = 0;
  return scene.Format();
}

CaptureTruth PlanCapture(const SimulationPreset& preset, const RigRenderer& renderer,
                         uint64_t seed) {
  const Rig& rig = renderer.rig();
  const RigConfig& config = rig.config();
  const SensorConfig& sensor = config.sensor;
  CaptureTruth plan;
  plan.seed = seed;
  plan.preset = preset.name;
  plan.pattern = preset.pattern;
  // Dot images: the shortest exposure puts the brightest dot image at peak_fill of the well.
  const double peak = renderer.ProbePeakRadiance();
  const double base = preset.peak_fill * sensor.full_well / (peak * sensor.sensitivity);
  for (double multiple : preset.bracket) plan.dot_exposures_s.push_back(base * multiple);
  // The monitor seen directly is brightest where it is seen most obliquely (intensity per area
  // constant at best: radiance <= exitance / cos): fill half the well there.
  const MonitorConfig& m = config.monitor;
  const double cos_edge = std::cos(std::min(rig.CameraTheta() + 0.15, 1.4));
  const double monitor_peak = m.white_exitance * m.Luminance(1.0) / cos_edge;
  plan.all_dots_exposure_s = 0.5 * sensor.full_well / (monitor_peak * sensor.sensitivity);
  plan.flat_exposure_s = plan.all_dots_exposure_s;
  const BoardConfig& b = config.board;
  plan.board_exposure_s =
      0.6 * sensor.full_well / (b.illumination * b.reflectance_white * sensor.sensitivity);
  plan.zhang_boards = renderer.ZhangBoardPoses(b.views, seed);
  plan.holder_board = renderer.HolderBoardPose();
  return plan;
}

void RenderCaptureRadiance(const RigRenderer& renderer, const CaptureTruth& plan, const CaptureId& id,
                           common::FloatImage* radiance) {
  using session::CaptureKind;
  const CameraIntrinsics& k = renderer.rig().config().intrinsics;
  switch (id.key.kind) {
    case CaptureKind::kDark:
      *radiance = common::FloatImage(k.width, k.height, 3);
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
  common::ThrowInvalidInput("capture", "the simulator does not render " + id.key.Format());
}

model::Vec2 CaptureWindowOrigin(const Rig& rig, const CaptureId& id) {
  // Board views are whole-sensor images; every other capture is the window.
  if (id.key.kind != session::CaptureKind::kBoardView) return model::Vec2::Zero();
  const SensorWindow& window = rig.config().window;
  return -model::Vec2(window.offset_x, window.offset_y);
}

std::unique_ptr<SimulatedSetup> MakeSimulatedSetup(SimulationPreset preset, uint64_t seed, int threads,
                                                   const TruthMaker& make_truth) {
  auto setup = std::make_unique<SimulatedSetup>();
  setup->preset = std::move(preset);
  setup->seed = seed;
  const SimulationPreset& p = setup->preset;
  setup->rig = std::make_unique<Rig>(p.rig);
  if (make_truth) {
    setup->material = make_truth(*setup->rig);
  } else {
    setup->material = std::make_unique<TruthMaterial>(
        TruthMaterial::FromPattern(p.pattern, p.rig.sample.texels_x, p.rig.sample.texels_y, p.eta, seed));
  }
  setup->renderer = std::make_unique<RigRenderer>(*setup->rig, setup->material.get(), threads);
  setup->plan = PlanCapture(p, *setup->renderer, seed);
  return setup;
}

}  // namespace svbtdf::simulate
