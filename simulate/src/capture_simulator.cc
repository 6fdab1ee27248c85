#include "svbtdf/simulate/capture_simulator.h"

#include <cmath>
#include <functional>

#include "svbtdf/common/interrupt.h"
#include "svbtdf/simulate/capture_render.h"
#include "svbtdf/common/progress.h"

namespace svbtdf {

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

namespace {

double ExposureOf(const CaptureTruth& plan, const session::CaptureKey& key) {
  using session::CaptureKind;
  switch (key.kind) {
    case CaptureKind::kDark:
    case CaptureKind::kDot: return plan.dot_exposures_s.at(key.bracket);
    case CaptureKind::kBoardView:
    case CaptureKind::kSamplePlaneView:
    case CaptureKind::kMonitorPoseView: return plan.board_exposure_s;
    case CaptureKind::kAllDots:
    case CaptureKind::kFiducials: return plan.all_dots_exposure_s;
    case CaptureKind::kFlatWhite: return plan.flat_exposure_s;
  }
  return 0.0;
}

}  // namespace

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

std::vector<CaptureId> CaptureList(const Rig& rig, const CaptureTruth& plan) {
  session::CaptureCounts counts;
  counts.brackets = static_cast<int>(plan.dot_exposures_s.size());
  counts.dark_frames = rig.config().dark_frames;
  counts.board_views = static_cast<int>(plan.zhang_boards.size());
  counts.sample_plane_views = 1;
  counts.all_dots = counts.fiducials = counts.flat_white = true;
  counts.dots = static_cast<int>(rig.dots().size());
  std::vector<CaptureId> list;
  for (const session::CaptureKey& key : session::CaptureOrder(counts)) {
    list.push_back({key, ExposureOf(plan, key)});
  }
  return list;
}

void RunCapture(const RigRenderer& renderer, const CaptureTruth& plan, CaptureSink& sink,
                const CaptureOptions& options) {
  const Rig& rig = renderer.rig();
  const std::vector<CaptureId> list = CaptureList(rig, plan);
  std::unique_ptr<ProgressBar> progress;
  if (options.progress) {
    progress = std::make_unique<ProgressBar>("simulate", static_cast<int64_t>(list.size()), "images");
  }
  FloatImage radiance;
  std::string rendered;  // identity of the radiance image in `radiance` (brackets share it)
  for (const CaptureId& id : list) {
    ThrowIfInterrupted("svbtdf simulate");
    if (sink.Contains(id)) {
      if (progress) progress->SkipAlreadyDone(1);
      continue;
    }
    // The brackets of one scene share its radiance image; dark frames differ only by their
    // noise, so they are not cached by frame.
    const std::string scene = SceneOf(id.key);
    if (scene != rendered) {
      RenderCaptureRadiance(renderer, plan, id, &radiance);
      rendered = id.key.kind == session::CaptureKind::kDark ? std::string() : scene;
    }
    sink.Write(id, renderer.Expose(radiance, id.exposure_s, options.seed, id.Stream(), CaptureWindowOrigin(rig, id)));
    if (progress) progress->Advance(1);
  }
}

}  // namespace svbtdf
