#pragma once
// The captures of the virtual rig: what each one shows the camera, its noise stream, the
// exposures the simulated lab plans (docs/simulator.md, "The capture"), and the simulated lab
// itself (SimulatedSetup). There is no capture loop here: `svbtdf simulate` is the capture loop
// of `svbtdf acquire` (acquire/capture_session.h) run with the simulated camera and display of
// acquire/sim_hardware.h, which render through these functions. So a simulated session holds
// exactly what a lab capture of the same plan would write.
//
// The noise of every image is a deterministic function of (seed, image identity), so an
// interrupted run that is resumed produces exactly the files an uninterrupted run would.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <string_view>

#include "svbtdf/session/capture_key.h"
#include "svbtdf/simulate/presets.h"
#include "svbtdf/simulate/renderer.h"
#include "svbtdf/simulate/spatial_btdf.h"
#include "svbtdf/simulate/truth_io.h"

namespace svbtdf::simulate {

// The identity of one stored capture: its session key and exposure.
struct CaptureId {
  session::CaptureKey key;
  double exposure_s = 0.0;
  uint64_t Stream() const;  // the noise stream of this image
};

// The noise stream of an image of `what` (dot q, board view, dark frame number: `index`) at
// exposure bracket `bracket`. The names are the simulator's own ("dots", "holder_board", "flat",
// ...), kept from version 1 of the simulator: changing them would change every simulated image.
uint64_t NoiseStream(std::string_view what, int index, int bracket);

// What the camera sees in a capture, whatever its bracket and repeat: captures of one scene share
// its radiance image.
std::string SceneOf(const session::CaptureKey& key);

// The exposures the capture will use (computed from the rig and the material by rendering the
// probe dot) and the board poses, so that the session can be planned before the images exist.
CaptureTruth PlanCapture(const SimulationPreset& preset, const RigRenderer& renderer, uint64_t seed);

// Radiance image of capture `id` (its kind and index; the exposure is applied by Expose).
void RenderCaptureRadiance(const RigRenderer& renderer, const CaptureTruth& plan, const CaptureId& id,
                           common::FloatImage* radiance);

// Where pixel (0, 0) of capture `id`'s image lies in the window's pixel coordinates: the Zhang
// board views are whole-sensor images, every other capture is the window (RigRenderer::Expose).
model::Vec2 CaptureWindowOrigin(const Rig& rig, const CaptureId& id);

// Everything the simulator derives from a preset: the rig, the material (the truth, analytic or
// Monte Carlo), the renderer and the capture plan (exposures, board poses). Held behind one
// pointer because the renderer keeps references to the rig and the material.
struct SimulatedSetup {
  SimulationPreset preset;
  uint64_t seed = 1;
  std::unique_ptr<Rig> rig;
  std::unique_ptr<SpatialBtdf> material;
  std::unique_ptr<RigRenderer> renderer;
  CaptureTruth plan;
};

// The truth a simulated lab shows its camera, made once its rig exists (the Monte Carlo truth is
// traced over the views the rig's camera has of the sample).
using TruthMaker = std::function<std::unique_ptr<SpatialBtdf>(const Rig& rig)>;

// Builds the setup of `preset` with the material `make_truth` returns, or the preset's analytic
// pattern material (seeded by `seed`) when it is empty. Throws svbtdf::Error for an impossible rig.
std::unique_ptr<SimulatedSetup> MakeSimulatedSetup(SimulationPreset preset, uint64_t seed, int threads,
                                                   const TruthMaker& make_truth = {});

}  // namespace svbtdf::simulate
