#include "svbtdf/acquire/simulated_session.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <nlohmann/json.hpp>

#include "svbtdf/acquire/capture_forecast.h"
#include "svbtdf/acquire/capture_plan.h"
#include "svbtdf/acquire/capture_session.h"
#include "svbtdf/acquire/sim_hardware.h"
#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/session/session.h"

namespace svbtdf::acquire {
namespace fs = std::filesystem;
namespace {

// OUT must be new, empty, or an unfinished simulation (session/ and truth/ only).
void CheckOutputFolder(const fs::path& out) {
  if (!fs::exists(out)) return;
  if (!fs::is_directory(out)) common::ThrowIoError(out.string(), "exists and is not a folder");
  for (const auto& entry : fs::directory_iterator(out)) {
    const std::string name = entry.path().filename().string();
    if (name != "session" && name != "truth") {
      common::ThrowInvalidInput(out.string(), "is not empty (it holds '" + name + "')", "choose a new output folder");
    }
  }
}

// A damaged session cannot be resumed: the journal is append-only, so a damaged image could not
// be rendered again under its key. Returns the number of images when the session is complete.
std::optional<int64_t> CheckResumable(const fs::path& session_folder, const simulate::SimulationOptions& options,
                                      const CapturePlan* plan) {
  if (!fs::exists(session_folder / "session.json")) return std::nullopt;
  const session::Session session = session::Session::Open(session_folder);
  const session::SessionVerification check = session.Verify(/*check_crc=*/true);
  if (!check.corrupt.empty() || !check.duplicated.empty()) {
    common::ThrowFormatError(session_folder.string(), "cannot be resumed: " + check.Summary(), "simulate into a new output folder");
  }
  if (!check.complete()) return std::nullopt;
  // A finished simulation of the same settings is done: a rerun says so and changes nothing. Of
  // other settings, it is never overwritten.
  const nlohmann::json& notes = session.rig_json().value("simulated", nlohmann::json::object());
  const bool same_eta = options.eta == 0.0 || session.rig().sample.eta == options.eta;
  // (The stored plan is the plan as simulated, AsSimulated: its dots and repeats are the plan's.)
  const nlohmann::json& stored = session.rig().acquisition_plan;
  const bool same_plan = !plan || (stored.is_object() && stored.value("dots", nlohmann::json()) == CapturePlanToJson(*plan)["dots"] &&
                                   stored.value("repeats", 0) == plan->repeats);
  if (notes.value("preset", "") != options.preset || notes.value("seed", uint64_t{0}) != options.seed ||
      notes.value("truth", "") != options.truth || !same_eta || notes.value("rig", "") != options.rig_source ||
      notes.value("plan", "") != (plan ? plan->name : "") || !same_plan) {
    common::ThrowInvalidInput(session_folder.string(),
                              "holds a complete simulated session of other settings (" + notes.dump() +
                                  "); it is never overwritten",
                              "choose a new output folder");
  }
  return static_cast<int64_t>(session.entries().size());
}

// What the manifest records beyond what the lab's acquisition writes: that the session is
// simulated, of which preset, seed and truth, and the monitor's black level a lab would measure.
nlohmann::json SimulationNotes(const simulate::SimulatedSetup& setup, const simulate::SimulationOptions& options,
                               const CapturePlan* plan) {
  nlohmann::json notes = {{"simulated", {{"preset", setup.preset.name}, {"seed", setup.seed}, {"truth", setup.plan.truth_kind}}},
                          {"monitor", {{"black_level", setup.rig->config().monitor.black_level}}}};
  if (!options.rig_source.empty()) notes["simulated"]["rig"] = options.rig_source;
  if (plan) notes["simulated"]["plan"] = plan->name;
  return notes;
}

// The simulated rig showing the plan's dots, with its board views and dark frames, so that every
// capture it asks for is one the simulator renders.
simulate::RigConfig RigForPlan(simulate::RigConfig rig, const CapturePlan& plan) {
  rig.dots.cols = plan.dot_cols;
  rig.dots.rows = plan.dot_rows;
  rig.dots.positions_px = plan.dots_px;
  rig.dots.radius_px = plan.dot_radius_px;
  // The plan's intensity is the linear luminance; the rig's level is what the display is sent.
  const simulate::MonitorConfig& m = rig.monitor;
  const double relative = std::clamp((plan.dot_intensity - m.black_level) / (1.0 - m.black_level), 1e-12, 1.0);
  rig.dots.level = std::pow(relative, 1.0 / m.gamma);
  if (plan.board_views >= 3) rig.board.views = plan.board_views;
  rig.dark_frames = plan.dark_frames;
  return rig;
}

// The plan as the simulated lab takes it. Its dot exposures are in seconds of the lab's camera, the
// simulator's in its own radiometric unit: they are scaled so that the shortest is the simulator's
// base exposure (the brightest dot image at 90% of full scale, which is how docs/capture.md tells
// a lab to choose it), the brackets keeping their ratios. The calibration captures, lit by the
// room, take the simulator's exposures. The notes it leaves out, and the boards (the simulator
// renders its own), are the simulated rig's.
CapturePlan AsSimulated(const CapturePlan& lab_plan, const simulate::SimulatedSetup& setup) {
  const CapturePlan simulated = PlanFromSimulation(setup);
  CapturePlan plan = ScaleExposures(lab_plan, simulated.exposures_s.front());
  plan.board_exposure_s = lab_plan.board_views + lab_plan.sample_plane_views > 0 ? simulated.board_exposure_s : 0.0;
  plan.all_dots_exposure_s = lab_plan.all_dots ? simulated.all_dots_exposure_s : 0.0;
  plan.flat_white_exposure_s = lab_plan.flat_white ? simulated.flat_white_exposure_s : 0.0;
  RigNotes& notes = plan.rig;
  const RigNotes& truth = simulated.rig;
  if (!(notes.monitor_distance_mm > 0)) notes.monitor_distance_mm = truth.monitor_distance_mm;
  if (notes.emission.empty()) notes.emission = truth.emission;
  if (notes.monitor_polarisation.empty()) notes.monitor_polarisation = truth.monitor_polarisation;
  notes.board = truth.board;
  notes.sample_plane_board = truth.sample_plane_board;
  if (!(notes.sample_width_mm > 0)) notes.sample_width_mm = truth.sample_width_mm;
  if (!(notes.sample_height_mm > 0)) notes.sample_height_mm = truth.sample_height_mm;
  if (notes.texels_x <= 0) notes.texels_x = truth.texels_x, notes.texels_y = truth.texels_y;
  if (!(notes.eta > 0)) notes.eta = truth.eta;
  if (notes.camera_response.empty()) notes.camera_response = truth.camera_response;
  if (std::isnan(notes.monitor_orientation_deg)) notes.monitor_orientation_deg = truth.monitor_orientation_deg;
  if (!(plan.pixel_pitch_mm > 0)) plan.pixel_pitch_mm = simulated.pixel_pitch_mm;
  return plan;
}

}  // namespace

SimulationOutput SimulateSession(const fs::path& out, const simulate::SimulationOptions& given, const CapturePlan* plan) {
  SimulationOutput output{out / "session", out / "truth"};
  simulate::SimulationOptions options = given;
  // Bad options are refused before anything is written.
  if (plan) options.rig = RigForPlan(simulate::PresetWithOptions(given).rig, *plan);
  simulate::PresetWithOptions(options);
  if (fs::is_directory(out)) {
    // Left by a kill mid-write; the command's lock says no other writer owns them.
    const int removed = common::RemoveStaleTemporaryFiles(out);
    if (removed > 0) spdlog::info("{}: removed {} temporary files left by an interrupted run", out.string(), removed);
  }
  CheckOutputFolder(out);
  if (const std::optional<int64_t> images = CheckResumable(output.session, options, plan)) {
    output.images = output.resumed = *images;
    output.already_complete = true;
    return output;
  }
  const std::shared_ptr<const simulate::SimulatedSetup> setup = simulate::PrepareSimulation(output.truth, options);

  auto world = std::make_shared<SimWorld>();
  SimDisplay display(world, SimDisplayInfo(*setup));
  SimCamera camera(world, setup, "sim");
  SimOperator op(world);
  AcquireOptions acquire_options;
  acquire_options.progress = options.progress;
  acquire_options.progress_label = "simulate";
  acquire_options.rig_additions = SimulationNotes(*setup, options, plan);
  acquire_options.before_capture = AnnounceCaptures(world);
  acquire_options.sleep = [](double) {};  // a simulated monitor settles at once
  const CapturePlan capture_plan = plan ? AsSimulated(*plan, *setup) : PlanFromSimulation(*setup);
  const AcquireResult result = Acquire(capture_plan, camera, display, op, output.session, acquire_options);
  output.resumed = result.already;
  output.images = result.already + result.captured;
  return output;
}

}  // namespace svbtdf::acquire
