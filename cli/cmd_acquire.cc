// svbtdf acquire: runs (or resumes) a capture session on the rig, or on the simulated rig
// (docs/capture.md).

#include <unistd.h>

#include <cstdio>
#include <iostream>
#include <memory>
#include <string>

#include "commands.h"
#include "svbtdf/acquire/capture_session.h"
#include "svbtdf/acquire/gphoto2_camera.h"
#include "svbtdf/acquire/libcamera_camera.h"
#include "svbtdf/acquire/sdl_display.h"
#include "svbtdf/acquire/sim_hardware.h"
#include "svbtdf/acquire/v4l2_camera.h"
#include "svbtdf/common/error.h"

namespace svbtdf::cli {
namespace {

// Exit code for a run that ended normally but left captures missing (skipped scenes), as
// `session verify` uses for an incomplete session.
constexpr int kIncompleteExitCode = 3;

struct AcquireArgs {
  std::string plan, plan_preset, camera, display, out;
  std::string calibration;  // prompt | as-is | skip; empty: prompt on a terminal, else as-is
  int retries = 3;
  double retry_backoff_s = 0.5;
};

// The rig: camera, display and operator, real or simulated.
struct LabRig {
  std::shared_ptr<acquire::SimWorld> world;
  std::unique_ptr<acquire::Camera> camera;
  std::unique_ptr<acquire::Display> display;
  std::unique_ptr<acquire::Operator> op;
};

std::pair<std::string, std::string> SplitSpec(const std::string& spec) {
  const size_t colon = spec.find(':');
  if (colon == std::string::npos) return {spec, ""};
  return {spec.substr(0, colon), spec.substr(colon + 1)};
}

std::unique_ptr<acquire::Camera> OpenCamera(const std::string& spec, LabRig& rig) {
  const auto [kind, target] = SplitSpec(spec);
  if (kind == "v4l2" && !target.empty()) return acquire::OpenV4l2Camera(target);
  if (kind == "libcamera" && !target.empty()) return acquire::OpenLibcameraCamera(target);
  if (kind == "gphoto2") return acquire::OpenGphoto2Camera(target);
  if (kind == "sim" && !target.empty()) {
    auto setup = acquire::LoadSimulation(target);
    rig.world = std::make_shared<acquire::SimWorld>();
    rig.display = std::make_unique<acquire::SimDisplay>(rig.world, acquire::SimDisplayInfo(*setup));
    return std::make_unique<acquire::SimCamera>(rig.world, setup, spec);
  }
  ThrowInvalidInput("--camera", "'" + spec + "' is not a camera",
                    "use v4l2:/dev/videoN, libcamera:ID, gphoto2[:PORT] or sim:DIR (see `svbtdf devices`)");
}

void OpenDisplay(const std::string& spec, LabRig& rig) {
  const auto [kind, target] = SplitSpec(spec);
  if (rig.world) {  // a simulated camera can only look at the simulated monitor
    if (spec != "sim") ThrowInvalidInput("--display", "a sim: camera needs --display sim, got '" + spec + "'");
    return;
  }
  if (spec == "sim") {
    rig.world = std::make_shared<acquire::SimWorld>();
    acquire::DisplayInfo info;
    info.id = "sim";
    info.width_px = 1920;
    info.height_px = 1080;
    rig.display = std::make_unique<acquire::SimDisplay>(rig.world, info);
    return;
  }
  if (kind == "sdl") {
    int index = 0;
    try {
      index = target.empty() ? 0 : std::stoi(target);
    } catch (const std::exception&) {
      ThrowInvalidInput("--display", "'" + spec + "': the display index must be a number");
    }
    rig.display = acquire::OpenSdlDisplay(index);
    return;
  }
  ThrowInvalidInput("--display", "'" + spec + "' is not a display", "use sdl[:INDEX] or sim");
}

std::unique_ptr<acquire::Operator> MakeOperator(const std::string& calibration, const LabRig& rig) {
  if (rig.world && rig.camera && dynamic_cast<acquire::SimCamera*>(rig.camera.get())) {
    return std::make_unique<acquire::SimOperator>(rig.world);  // the virtual lab arranges itself
  }
  const std::string mode = !calibration.empty() ? calibration : (::isatty(STDIN_FILENO) ? "prompt" : "as-is");
  if (mode == "prompt") return std::make_unique<acquire::ConsoleOperator>(std::cin, std::cerr);
  if (mode == "skip") return std::make_unique<acquire::UnattendedOperator>(acquire::UnattendedPolicy::kSkip);
  return std::make_unique<acquire::UnattendedOperator>(acquire::UnattendedPolicy::kAsIs);
}

void RunAcquire(const AcquireArgs& args) {
  if (args.plan.empty() == args.plan_preset.empty()) {
    ThrowInvalidInput("--plan", "give exactly one of --plan PLAN and --plan-preset NAME");
  }
  if (args.retries < 0 || args.retries > 100) ThrowInvalidInput("--retries", "must lie in [0, 100]");
  // The plan is checked before any hardware is touched.
  const acquire::CapturePlan plan =
      args.plan.empty() ? acquire::MakePlanPreset(args.plan_preset) : acquire::ReadCapturePlan(args.plan);
  LabRig rig;
  rig.camera = OpenCamera(args.camera, rig);
  OpenDisplay(args.display, rig);
  rig.op = MakeOperator(args.calibration, rig);
  acquire::AcquireOptions options;
  options.retries = args.retries;
  options.retry_backoff_s = args.retry_backoff_s;
  const acquire::AcquireResult result = acquire::Acquire(plan, *rig.camera, *rig.display, *rig.op, args.out, options);
  std::printf("acquired %lld images in %.1f s (%lld were already there, %lld retried captures); %lld of %lld planned\n",
              static_cast<long long>(result.captured), result.seconds, static_cast<long long>(result.already),
              static_cast<long long>(result.retries), static_cast<long long>(result.already + result.captured),
              static_cast<long long>(result.planned));
  if (!result.complete()) {
    std::printf("%lld captures were skipped; run the same command again to take them\n",
                static_cast<long long>(result.skipped));
    std::fflush(stdout);
    throw CLI::RuntimeError(kIncompleteExitCode);
  }
}

}  // namespace

void AddAcquireCommand(CLI::App& app) {
  auto args = std::make_shared<AcquireArgs>();
  CLI::App* acquire = app.add_subcommand("acquire", "Capture (or resume) a session on the rig (docs/capture.md)");
  acquire->add_option("--plan", args->plan, "capture plan file (JSON, docs/capture.md)");
  acquire->add_option("--plan-preset", args->plan_preset, "built-in plan: the captures of `svbtdf simulate --preset NAME`")
      ->check(CLI::IsMember(acquire::PlanPresetNames()));
  acquire->add_option("--camera", args->camera, "v4l2:/dev/videoN, libcamera:ID, gphoto2[:PORT] or sim:DIR")->required();
  acquire->add_option("--display", args->display, "sdl[:INDEX] or sim")->required();
  acquire->add_option("--out", args->out, "session folder (new, or a session of the same plan to resume)")->required();
  acquire->add_option("--retries", args->retries, "attempts after a failed capture before stopping")->capture_default_str();
  acquire->add_option("--retry-backoff", args->retry_backoff_s, "seconds before the first retry (doubling)")
      ->capture_default_str();
  acquire->add_option("--calibration", args->calibration,
                      "prompt: ask the operator; as-is: capture without asking; skip: leave operator captures missing "
                      "(default: prompt on a terminal, else as-is)")
      ->check(CLI::IsMember({"prompt", "as-is", "skip"}));
  acquire->callback([args] { RunAcquire(*args); });
}

}  // namespace svbtdf::cli
