#pragma once
// Simulated rig hardware for `svbtdf acquire --camera sim:DIR --display sim` and the tests: a
// headless display that remembers (and can rasterise) the pattern it shows, a camera that renders
// with the simulator (simulate/capture_render.h) what the rig of the simulation in DIR would see
// of that pattern, and an operator that arranges the virtual scene (sample in or out, board
// poses). They share one SimWorld, the state of the virtual lab.

#include <filesystem>
#include <map>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "svbtdf/acquire/camera.h"
#include "svbtdf/acquire/capture_plan.h"
#include "svbtdf/acquire/capture_session.h"
#include "svbtdf/acquire/display.h"
#include "svbtdf/common/image_io.h"
#include "svbtdf/session/capture_key.h"

namespace svbtdf::simulate {
struct SimulatedSetup;
}

namespace svbtdf::acquire {

// What is in front of the virtual camera.
struct SimWorld {
  Pattern pattern;              // on the monitor (black until something is shown)
  Scene scene = Scene::kSample;
  int view = 0;
  int patterns_shown = 0;
  // The capture the loop says it takes next (AnnounceCaptures); unset when nobody says.
  std::optional<session::CaptureKey> announced;
};

// AcquireOptions::before_capture for a simulated rig: the loop tells the virtual lab which capture
// it takes, so that a resumed session's dark frame n gets dark frame n's noise (a camera counting
// its own captures would start again at 0).
std::function<void(const PlannedCapture&)> AnnounceCaptures(std::shared_ptr<SimWorld> world);

class SimDisplay : public Display {
 public:
  SimDisplay(std::shared_ptr<SimWorld> world, DisplayInfo info);
  DisplayInfo Info() const override { return info_; }
  // Presented at once (the simulated monitor has no refresh).
  Presentation Show(const Pattern& pattern) override;
  // The code values a real monitor would show now (pattern_raster.h).
  std::vector<uint8_t> Raster() const;

 private:
  std::shared_ptr<SimWorld> world_;
  DisplayInfo info_;
};

// The display of the simulated rig: the monitor's size and gamma.
DisplayInfo SimDisplayInfo(const simulate::SimulatedSetup& setup);

class SimOperator : public Operator {
 public:
  explicit SimOperator(std::shared_ptr<SimWorld> world) : world_(std::move(world)) {}
  bool Prepare(Scene scene, int view, const std::string& instruction) override;

 private:
  std::shared_ptr<SimWorld> world_;
};

// Renders the current SimWorld with the simulator. The noise stream of each image is the one
// `svbtdf simulate` uses for the same capture (dot q at bracket e, dark frame n, board view v),
// so a fresh acquisition with the simulation's plan stores the simulator's very bytes. Repeated
// captures of one scene (dark frames, repeats) are numbered as the loop announces them
// (AnnounceCaptures), else in the order this camera takes them.
// Dots that are not the rig's (another plan's grid, radius or intensity) are rendered too, with
// noise streams of their own.
class SimCamera : public Camera {
 public:
  SimCamera(std::shared_ptr<SimWorld> world, std::shared_ptr<const simulate::SimulatedSetup> setup, std::string id);
  CameraInfo Info() const override;
  void SetExposure(const ExposureSettings& settings) override;
  Frame Capture() override;

 private:
  struct Identified;  // the simulator's CaptureId of what is in view
  Identified Identify() const;
  int ExposureIndex() const;

  std::shared_ptr<SimWorld> world_;
  std::shared_ptr<const simulate::SimulatedSetup> setup_;
  std::string id_;
  ExposureSettings settings_;
  std::map<std::pair<std::string, int>, int> taken_;  // captures per (scene, bracket)
  common::FloatImage radiance_;   // of the last capture
  std::string rendered_;  // its scene (SceneOf), empty when it cannot be reused
};

// `sim:DIR`: loads the simulation in DIR (simulate/capture_render.h, LoadSimulatedSetup).
std::shared_ptr<const simulate::SimulatedSetup> LoadSimulation(const std::filesystem::path& dir);

// A camera wrapper that injects faults, for tests: capture number `fail_at` (1-based, counting
// every Capture() call) fails with Error(kHardware) `fail_count` times in a row (then captures
// succeed again), or, with `unplug`, every capture from `fail_at` on fails ("cable pulled").
struct FaultPlan {
  int fail_at = 0;      // 0: never
  int fail_count = 1;
  bool unplug = false;
};
class FaultInjectingCamera : public Camera {
 public:
  FaultInjectingCamera(Camera& inner, FaultPlan plan) : inner_(inner), plan_(plan) {}
  CameraInfo Info() const override { return inner_.Info(); }
  void SetExposure(const ExposureSettings& settings) override;
  Frame Capture() override;
  int calls() const { return calls_; }
  int failures() const { return failures_; }

 private:
  Camera& inner_;
  FaultPlan plan_;
  int calls_ = 0;
  int failures_ = 0;
};

}  // namespace svbtdf::acquire
