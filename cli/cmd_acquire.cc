// svbtdf acquire: runs (or resumes) a capture session on the rig, or on the simulated rig
// (docs/capture.md).

#include <cstdio>
#include <memory>
#include <string>

#include "commands.h"
#include "svbtdf/common/folder_lock.h"
#include "svbtdf/acquire/capture_session.h"
#include "svbtdf/acquire/lab_rig.h"
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

void RunAcquire(const AcquireArgs& args) {
  if (args.plan.empty() == args.plan_preset.empty()) {
    common::ThrowInvalidInput("--plan", "give exactly one of --plan PLAN and --plan-preset NAME");
  }
  if (args.retries < 0 || args.retries > 100) common::ThrowInvalidInput("--retries", "must lie in [0, 100]");
  // The plan is checked before any hardware is touched.
  const acquire::CapturePlan plan =
      args.plan.empty() ? acquire::MakePlanPreset(args.plan_preset) : acquire::ReadCapturePlan(args.plan);
  const common::FolderLock lock = common::FolderLock::Acquire(args.out, "svbtdf acquire");
  acquire::LabRig rig = acquire::OpenLabRig(args.camera, args.display, args.calibration);
  acquire::AcquireOptions options;
  options.retries = args.retries;
  options.retry_backoff_s = args.retry_backoff_s;
  if (rig.world) options.before_capture = acquire::AnnounceCaptures(rig.world);
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
