#pragma once
// `svbtdf simulate`: a capture session of a known material, taken by the one capture loop
// (capture_session.h, Acquire) with the simulated camera, display and operator of
// sim_hardware.h and the plan of the simulated lab (PlanFromSimulation), beside its ground truth.
// So a simulated session is, byte for byte, what `svbtdf acquire` writes on the simulated rig,
// and the simulator cannot drift from a lab capture.

#include <cstdint>
#include <filesystem>

#include "svbtdf/acquire/capture_plan.h"
#include "svbtdf/simulate/simulation.h"

namespace svbtdf::acquire {

struct SimulationOutput {
  std::filesystem::path session;  // OUT/session
  std::filesystem::path truth;    // OUT/truth
  int64_t images = 0;             // images in the session
  int64_t resumed = 0;            // of which were already there
  bool already_complete = false;  // a rerun of a finished simulation of the same settings: nothing done
};

// Simulates `options` into OUT/session and OUT/truth. A folder holding an unfinished simulation
// of the same settings is resumed (byte-identical to an uninterrupted run); any other non-empty
// OUT is refused (svbtdf::Error(kInvalidInput)). A complete session is never touched again: of
// the same preset, seed, truth and eta the call returns at once (already_complete), else refuses.
// Ctrl-C ends it between images with Error(kInterrupted), leaving a resumable session.
//
// With a `plan` (`svbtdf simulate --plan`) the capture is that plan's: its dots replace the
// rig's grid (positions, radius, intensity), its board views, dark frames, brackets' ratios and
// repeats are the simulated ones; its shortest dot exposure becomes the simulator's base exposure
// (seconds of a lab's camera mean nothing to the simulator's radiometric unit) and the
// calibration captures take the simulator's exposures; the rig notes it leaves out, and the
// boards (the simulator renders its own), are the simulated rig's, so the session calibrates like
// any other.
SimulationOutput SimulateSession(const std::filesystem::path& out, const simulate::SimulationOptions& options,
                                 const CapturePlan* plan = nullptr);

}  // namespace svbtdf::acquire
