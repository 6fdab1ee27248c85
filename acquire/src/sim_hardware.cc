#include "svbtdf/acquire/sim_hardware.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>

#include "svbtdf/acquire/pattern_raster.h"
#include "svbtdf/common/error.h"
#include "svbtdf/session/fiducials.h"
#include "svbtdf/simulate/capture_render.h"
#include "svbtdf/simulate/simulation.h"

namespace svbtdf::acquire {
namespace {

[[noreturn]] void NotSimulated(const std::string& camera, const std::string& what) {
  throw common::Error(common::ErrorKind::kInvalidInput, camera, "cannot simulate " + what,
              "the simulated rig renders the captures of docs/capture.md's scenes only");
}

}  // namespace

SimDisplay::SimDisplay(std::shared_ptr<SimWorld> world, DisplayInfo info) : world_(std::move(world)), info_(std::move(info)) {}

Presentation SimDisplay::Show(const Pattern& pattern) {
  if (!(pattern.intensity >= 0.0 && pattern.intensity <= 1.0) || !std::isfinite(pattern.x_px) ||
      !std::isfinite(pattern.y_px)) {
    common::ThrowInvalidInput(info_.id, "pattern with a non-finite position or an intensity outside [0, 1]");
  }
  world_->pattern = pattern;
  ++world_->patterns_shown;
  return {MonotonicSeconds(), 0, false};
}

std::vector<uint8_t> SimDisplay::Raster() const {
  return RasterizePattern(world_->pattern, info_.width_px, info_.height_px, info_.gamma);
}

DisplayInfo SimDisplayInfo(const simulate::SimulatedSetup& setup) {
  const simulate::MonitorConfig& m = setup.rig->config().monitor;
  DisplayInfo info;
  info.id = "sim";
  info.width_px = static_cast<int>(std::floor(m.width / m.pixel_pitch));
  info.height_px = static_cast<int>(std::floor(m.height / m.pixel_pitch));
  info.pixel_pitch_mm = m.pixel_pitch * 1000.0;
  info.gamma = m.gamma;
  return info;
}

std::function<void(const PlannedCapture&)> AnnounceCaptures(std::shared_ptr<SimWorld> world) {
  return [world = std::move(world)](const PlannedCapture& capture) {
    world->announced = session::CaptureKey::Parse(capture.key);
  };
}

bool SimOperator::Prepare(Scene scene, int view, const std::string& instruction) {
  world_->scene = scene;
  world_->view = view;
  return true;
}

struct SimCamera::Identified {
  simulate::CaptureId id;
  std::optional<simulate::Dot> free_dot;  // a dot that is not one of the rig's grid
};

SimCamera::SimCamera(std::shared_ptr<SimWorld> world, std::shared_ptr<const simulate::SimulatedSetup> setup, std::string id)
    : world_(std::move(world)), setup_(std::move(setup)), id_(std::move(id)) {}

CameraInfo SimCamera::Info() const {
  const simulate::CameraIntrinsics& k = setup_->rig->config().intrinsics;
  CameraInfo info;
  info.id = id_;
  info.model = "svbtdf simulated camera (preset " + setup_->preset.name + ")";
  info.formats = {"RGB" + std::to_string(setup_->rig->config().sensor.bit_depth) + " " + std::to_string(k.width) + "x" +
                  std::to_string(k.height)};
  info.min_exposure_s = 1e-7;
  info.max_exposure_s = 3600.0;
  info.frame_width = k.width;
  info.frame_height = k.height;
  info.frame_channels = 3;
  info.frame_bits = setup_->rig->config().sensor.bit_depth;
  info.window = setup_->rig->config().window;
  return info;
}

void SimCamera::SetExposure(const ExposureSettings& settings) {
  if (!(settings.exposure_s > 0) || !std::isfinite(settings.exposure_s)) {
    common::ThrowInvalidInput(id_, "exposure must be positive");
  }
  if (settings.gain != 1.0) common::ThrowInvalidInput(id_, "the simulated sensor has only gain 1");
  settings_ = settings;
}

// The simulator numbers brackets by the dot exposures; -1 for any other exposure.
int SimCamera::ExposureIndex() const {
  const std::vector<double>& exposures = setup_->plan.dot_exposures_s;
  for (size_t e = 0; e < exposures.size(); ++e) {
    if (std::abs(exposures[e] - settings_.exposure_s) <= 1e-9 * exposures[e]) return static_cast<int>(e);
  }
  return -1;
}

SimCamera::Identified SimCamera::Identify() const {
  using session::CaptureKey;
  const Pattern& p = world_->pattern;
  const simulate::Rig& rig = *setup_->rig;
  // Calibration captures are bracket 0 in `svbtdf simulate` (all_dots/e0, flat_white/e0).
  const int e = std::max(ExposureIndex(), 0);
  const auto known = [&](const CaptureKey& key) { return Identified{{key, settings_.exposure_s}, std::nullopt}; };
  if (p.kind == Pattern::Kind::kBlack) {
    if (world_->scene == Scene::kBoardView) {
      if (world_->view >= static_cast<int>(setup_->plan.zhang_boards.size())) {
        NotSimulated(id_, "board view " + std::to_string(world_->view) + ": the simulation has " +
                              std::to_string(setup_->plan.zhang_boards.size()) + " board poses");
      }
      return known(CaptureKey::BoardView(world_->view));
    }
    if (world_->scene == Scene::kBoardInHolder) return known(CaptureKey::SamplePlaneView(world_->view));
    return known(CaptureKey::Dark(e, 0));
  }
  if (world_->scene == Scene::kNoSample && p.kind == Pattern::Kind::kAllDots) {
    if (p.all_dots_px.size() == rig.dots().size()) return known(CaptureKey::AllDots());
    // The fiducial dots, which the simulator renders as its `fiducials` capture.
    const std::vector<int> fiducials = session::FiducialDots(rig.config().dots.cols, rig.config().dots.rows);
    bool same = p.all_dots_px.size() == fiducials.size();
    for (size_t k = 0; same && k < fiducials.size(); ++k) {
      const simulate::Dot& dot = rig.dots()[fiducials[k]];
      same = p.all_dots_px[k] == std::pair<double, double>(dot.drawn_x, dot.drawn_y);
    }
    if (!same) NotSimulated(id_, "a set of lit dots other than the rig's dots or its fiducial dots");
    return known(CaptureKey::Fiducials());
  }
  if (world_->scene == Scene::kNoSample && p.kind == Pattern::Kind::kFlatWhite && p.intensity == 1.0) {
    return known(CaptureKey::FlatWhite());
  }
  if (world_->scene == Scene::kSample && p.kind == Pattern::Kind::kDot) {
    const simulate::MonitorConfig& m = rig.config().monitor;
    // (A plan's intensity comes back from the displayed level through the gamma curve, so to
    // within rounding.)
    const bool rig_like = p.dot_radius_px == rig.config().dots.radius_px &&
                          std::abs(p.intensity - m.Luminance(rig.config().dots.level)) <= 1e-12;
    for (size_t q = 0; rig_like && q < rig.dots().size(); ++q) {
      const simulate::Dot& dot = rig.dots()[q];
      if (p.x_px == dot.drawn_x && p.y_px == dot.drawn_y) return known(CaptureKey::Dot(static_cast<int>(q), e));
    }
    // Any other dot: rendered by the simulator all the same, with a noise stream of its own.
    return {{CaptureKey::Dot(-1, e), settings_.exposure_s},
            rig.DotAt(p.x_px, p.y_px, p.dot_radius_px, m.Luminance(std::pow(p.intensity, 1.0 / m.gamma)))};
  }
  NotSimulated(id_, "this pattern in this scene (" + SceneInstruction(world_->scene, world_->view) + ")");
}

Frame SimCamera::Capture() {
  Identified what = Identify();
  simulate::CaptureId& id = what.id;
  const bool dark = id.key.kind == session::CaptureKind::kDark;
  // The n-th capture of the same thing: dark frame n, or a repeat with its own noise. (All
  // free dots of a bracket share one count.)
  const std::string scene = what.free_dot ? "free_dot" : simulate::SceneOf(id.key);
  int n = taken_[{scene, id.key.bracket}]++;
  const std::optional<session::CaptureKey>& announced = world_->announced;
  if (!what.free_dot && announced && simulate::SceneOf(*announced) == scene && announced->bracket == id.key.bracket) {
    n = announced->repeat;
  }
  uint64_t stream;
  if (dark) {
    id.key.repeat = n;
    stream = id.Stream();
  } else {
    const uint64_t base = what.free_dot ? simulate::NoiseStream("free_dot", 0, id.key.bracket) : id.Stream();
    stream = base ^ (static_cast<uint64_t>(n) * 0xd1b54a32d192ed03ULL);
  }
  // Another plan's dot brackets: noise streams of their own rather than bracket 0's. (The
  // calibration captures have one exposure each, bracket 0 in the simulator whatever it is.)
  const bool bracketed = id.key.kind == session::CaptureKind::kDot || dark;
  if (bracketed && ExposureIndex() < 0) stream ^= std::hash<double>{}(settings_.exposure_s) * 0x9e3779b97f4a7c15ULL;
  // Brackets and repeats of one scene share its radiance image, as in the simulator.
  if (what.free_dot) {
    const simulate::Dot& dot = *what.free_dot;
    stream ^= std::hash<double>{}(dot.position.x()) * 31 + std::hash<double>{}(dot.position.y());
    setup_->renderer->RenderDot(dot, &radiance_);
    rendered_.clear();
  } else if (dark || scene != rendered_) {
    simulate::RenderCaptureRadiance(*setup_->renderer, setup_->plan, id, &radiance_);
    rendered_ = dark ? std::string() : scene;
  }
  const common::CameraImage image = setup_->renderer->Expose(radiance_, settings_.exposure_s, setup_->seed, stream,
                                                     simulate::CaptureWindowOrigin(*setup_->rig, id));
  Frame frame;
  frame.width = image.width;
  frame.height = image.height;
  frame.channels = image.channels;
  frame.bits_per_sample = image.bits_per_sample;
  frame.linear = setup_->rig->config().sensor.response == "linear";
  frame.exposure_s = settings_.exposure_s;
  frame.gain = settings_.gain;
  frame.pixels = image.pixels;
  return frame;
}

std::shared_ptr<const simulate::SimulatedSetup> LoadSimulation(const std::filesystem::path& dir) {
  return simulate::LoadSimulatedSetup(dir, /*threads=*/0);
}

void FaultInjectingCamera::SetExposure(const ExposureSettings& settings) {
  if (plan_.unplug && plan_.fail_at > 0 && calls_ >= plan_.fail_at) {
    ++failures_;
    throw common::Error(common::ErrorKind::kHardware, inner_.Info().id, "cable pulled");
  }
  inner_.SetExposure(settings);
}

Frame FaultInjectingCamera::Capture() {
  ++calls_;
  const bool failing = plan_.fail_at > 0 && calls_ >= plan_.fail_at &&
                       (plan_.unplug || calls_ < plan_.fail_at + plan_.fail_count);
  if (failing) {
    ++failures_;
    throw common::Error(common::ErrorKind::kHardware, inner_.Info().id, plan_.unplug ? "cable pulled" : "injected capture failure");
  }
  return inner_.Capture();
}

}  // namespace svbtdf::acquire
