// svbtdf plan: what a capture will be before it is taken -- images, duration, disk, the angles
// the dots cover and whether they are dense enough for a roughness (docs/capture.md, "Planning a
// capture").

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "svbtdf/acquire/capture_forecast.h"
#include "svbtdf/common/error.h"
#include "svbtdf/simulate/presets.h"

namespace svbtdf::cli {
namespace {

struct PlanArgs {
  std::string plan, rig, preset = "demo";
  std::vector<double> roughness = {0.05, 0.1, 0.2, 0.4};
  double frame_time_s = 0.0;
  double shortest_exposure_s = 0.0;
};

void RunPlan(const PlanArgs& args) {
  for (double r : args.roughness) {
    if (!(r > 0.0 && r <= 2.0)) common::ThrowInvalidInput("--roughness", "each GGX alpha must lie in (0, 2], got " + std::to_string(r));
  }
  if (args.frame_time_s < 0.0) common::ThrowInvalidInput("--frame-time", "must be > 0 seconds");
  if (args.shortest_exposure_s < 0.0) common::ThrowInvalidInput("--shortest-exposure", "must be > 0 seconds");
  acquire::CapturePlan plan =
      args.plan.empty() ? acquire::MakePlanPreset(args.preset) : acquire::ReadCapturePlan(args.plan);
  simulate::RigFile rig = args.rig.empty() ? simulate::RigFileOfPreset(args.preset) : simulate::ReadRigFile(args.rig);
  if (args.frame_time_s > 0) rig.frame_time_s = args.frame_time_s;
  // A preset's plan is in the simulator's radiometric unit: its shortest dot exposure becomes one
  // frame time unless told otherwise. A lab's plan is in seconds already.
  double scale = 1.0;
  if (args.shortest_exposure_s > 0 || args.plan.empty()) {
    plan = acquire::ScaleExposures(plan, args.shortest_exposure_s > 0 ? args.shortest_exposure_s : rig.frame_time_s, &scale);
  }
  const std::string rig_name = args.rig.empty() ? "preset " + args.preset : args.rig;
  acquire::CaptureForecast forecast = acquire::ForecastCapture(plan, rig, rig_name, args.roughness);
  forecast.exposure_scale = scale;
  std::fputs(acquire::FormatForecast(forecast).c_str(), stdout);
}

}  // namespace

void AddPlanCommand(CLI::App& app) {
  auto args = std::make_shared<PlanArgs>();
  CLI::App* plan = app.add_subcommand(
      "plan", "Predict a capture before taking it: images, duration, disk, the dots' angles and density (docs/capture.md)");
  plan->add_option("--plan", args->plan, "capture plan file (JSON, docs/capture.md); default: the preset's plan");
  plan->add_option("--rig", args->rig, "rig file (JSON, docs/capture.md); default: the preset's rig");
  plan->add_option("--preset", args->preset, "simulator preset for what --plan or --rig does not give")
      ->check(CLI::IsMember(simulate::PresetNames()))
      ->capture_default_str();
  plan->add_option("--roughness", args->roughness, "GGX alphas to check the dot spacing against")
      ->delimiter(',')
      ->capture_default_str();
  plan->add_option("--frame-time", args->frame_time_s,
                   "the camera's measured frame time in seconds (default: the rig file's camera.frame_time_s)");
  plan->add_option("--shortest-exposure", args->shortest_exposure_s,
                   "scale the plan's exposures so that its shortest dot exposure is this many seconds (default for "
                   "a preset's plan, which is in the simulator's units: one frame time)");
  plan->callback([args] { RunPlan(*args); });
}

}  // namespace svbtdf::cli
