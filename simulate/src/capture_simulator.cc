#include "svbtdf/simulate/capture_simulator.h"

#include <cmath>
#include <functional>

#include "svbtdf/common/interrupt.h"
#include "svbtdf/simulate/capture_render.h"
#include "svbtdf/common/progress.h"

namespace svbtdf {

uint64_t CaptureId::Stream() const {
  const uint64_t kind_hash = std::hash<std::string>{}(kind);
  return kind_hash * 0x9e3779b97f4a7c15ULL ^ (uint64_t(index) << 16) ^ uint64_t(exposure_index);
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
  std::vector<CaptureId> list;
  for (size_t e = 0; e < plan.dot_exposures_s.size(); ++e) {
    for (int n = 0; n < rig.config().dark_frames; ++n) {
      list.push_back({"dark", n, static_cast<int>(e), plan.dot_exposures_s[e]});
    }
  }
  for (size_t v = 0; v < plan.zhang_boards.size(); ++v) {
    list.push_back({"board", static_cast<int>(v), 0, plan.board_exposure_s});
  }
  list.push_back({"holder_board", 0, 0, plan.board_exposure_s});
  list.push_back({"all_dots", 0, 0, plan.all_dots_exposure_s});
  list.push_back({"fiducials", 0, 0, plan.all_dots_exposure_s});
  list.push_back({"flat", 0, 0, plan.flat_exposure_s});
  for (size_t q = 0; q < rig.dots().size(); ++q) {
    for (size_t e = 0; e < plan.dot_exposures_s.size(); ++e) {
      list.push_back({"dots", static_cast<int>(q), static_cast<int>(e), plan.dot_exposures_s[e]});
    }
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
    const std::string key = id.kind + "/" + std::to_string(id.index);
    if (key != rendered) {
      RenderCaptureRadiance(renderer, plan, id, &radiance);
      // Dark frames differ only by their noise, so they are not cached by index.
      rendered = id.kind == "dark" ? std::string() : key;
    }
    sink.Write(id, renderer.Expose(radiance, id.exposure_s, options.seed, id.Stream(), CaptureWindowOrigin(rig, id)));
    if (progress) progress->Advance(1);
  }
}

}  // namespace svbtdf
