#include "svbtdf/acquire/simulated_session.h"

#include <spdlog/spdlog.h>

#include <memory>
#include <optional>
#include <nlohmann/json.hpp>

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
std::optional<int64_t> CheckResumable(const fs::path& session_folder, const simulate::SimulationOptions& options) {
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
  if (notes.value("preset", "") != options.preset || notes.value("seed", uint64_t{0}) != options.seed ||
      notes.value("truth", "") != options.truth || !same_eta) {
    common::ThrowInvalidInput(session_folder.string(),
                              "holds a complete simulated session of other settings (" + notes.dump() +
                                  "); it is never overwritten",
                              "choose a new output folder");
  }
  return static_cast<int64_t>(session.entries().size());
}

// What the manifest records beyond what the lab's acquisition writes: that the session is
// simulated, of which preset, seed and truth, and the monitor's black level a lab would measure.
nlohmann::json SimulationNotes(const simulate::SimulatedSetup& setup) {
  return {{"simulated", {{"preset", setup.preset.name}, {"seed", setup.seed}, {"truth", setup.plan.truth_kind}}},
          {"monitor", {{"black_level", setup.rig->config().monitor.black_level}}}};
}

}  // namespace

SimulationOutput SimulateSession(const fs::path& out, const simulate::SimulationOptions& options) {
  SimulationOutput output{out / "session", out / "truth"};
  simulate::PresetWithOptions(options);  // bad options are refused before anything is written
  if (fs::is_directory(out)) {
    // Left by a kill mid-write; the command's lock says no other writer owns them.
    const int removed = common::RemoveStaleTemporaryFiles(out);
    if (removed > 0) spdlog::info("{}: removed {} temporary files left by an interrupted run", out.string(), removed);
  }
  CheckOutputFolder(out);
  if (const std::optional<int64_t> images = CheckResumable(output.session, options)) {
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
  acquire_options.rig_additions = SimulationNotes(*setup);
  acquire_options.before_capture = AnnounceCaptures(world);
  acquire_options.sleep = [](double) {};  // a simulated monitor settles at once
  const AcquireResult result = Acquire(PlanFromSimulation(*setup), camera, display, op, output.session, acquire_options);
  output.resumed = result.already;
  output.images = result.already + result.captured;
  return output;
}

}  // namespace svbtdf::acquire
