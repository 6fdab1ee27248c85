#pragma once
// Rendering one capture of the synthetic rig by its identity, and rebuilding the rig of a
// finished simulation from its output folder. `svbtdf simulate` (RunCapture) and the simulated
// camera of `svbtdf acquire` (acquire/sim_hardware.h) both render through these, so a simulated
// acquisition stores the very images the simulator writes for the same keys.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>

#include "svbtdf/simulate/capture_simulator.h"
#include "svbtdf/simulate/presets.h"
#include "svbtdf/simulate/renderer.h"
#include "svbtdf/simulate/truth_io.h"
#include "svbtdf/simulate/truth_material.h"

namespace svbtdf {

// Radiance image of capture `id` (its kind and index; the exposure is applied by Expose).
void RenderCaptureRadiance(const RigRenderer& renderer, const CaptureTruth& plan, const CaptureId& id,
                           FloatImage* radiance);

// Where pixel (0, 0) of capture `id`'s image lies in the window's pixel coordinates: the Zhang
// board views are whole-sensor images, every other capture is the window (RigRenderer::Expose).
Vec2 CaptureWindowOrigin(const Rig& rig, const CaptureId& id);

// Everything the simulator derives from a preset: the rig, the material, the renderer and the
// capture plan (exposures, board poses). Held behind one pointer because the renderer keeps
// references to the rig and the material.
struct SimulatedSetup {
  SimulationPreset preset;
  uint64_t seed = 1;
  std::unique_ptr<Rig> rig;
  std::unique_ptr<TruthMaterial> material;
  std::unique_ptr<RigRenderer> renderer;
  CaptureTruth plan;
};

// Builds the setup of `preset` (eta > 0 overrides the preset's); throws svbtdf::Error for an
// unknown preset or an impossible rig.
std::unique_ptr<SimulatedSetup> MakeSimulatedSetup(SimulationPreset preset, uint64_t seed, int threads);

// Rebuilds the setup of the simulation in OUT (the folder `svbtdf simulate --out OUT` wrote), from
// OUT/truth/rig.json (preset, seed, exposures, board poses) and OUT/truth/material.json (eta), and
// checks that the rebuilt rig and plan equal the recorded ones. Throws svbtdf::Error naming the
// file when OUT is not a simulation or does not match what this build would simulate.
std::unique_ptr<SimulatedSetup> LoadSimulatedSetup(const std::filesystem::path& out, int threads);

}  // namespace svbtdf
