#pragma once
// Runs a whole synthetic capture (docs/simulator.md, "The capture"): dark frames, Zhang board
// views, the board in the sample holder, the all-dots image and a flat white without the sample,
// then every dot image at every exposure of the bracket. Images go to a CaptureSink as soon as
// they are made (one radiance image and one stored image in memory at a time), so memory stays
// bounded by the rig's precomputation whatever the number of dots.
//
// The noise of every image is a deterministic function of (seed, image identity), so an
// interrupted run that is resumed (the sink reports what it already has) produces exactly the
// files an uninterrupted run would.

#include <cstdint>
#include <string>
#include <string_view>

#include "svbtdf/session/capture_key.h"
#include "svbtdf/simulate/presets.h"
#include "svbtdf/simulate/renderer.h"
#include "svbtdf/simulate/truth_io.h"

namespace svbtdf {

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

// Where the captures go: the session writer in the command line, memory in the tests.
class CaptureSink {
 public:
  virtual ~CaptureSink() = default;
  // True when this capture is already stored (a resumed run skips it).
  virtual bool Contains(const CaptureId& id) const = 0;
  virtual void Write(const CaptureId& id, const CameraImage& image) = 0;
};

struct CaptureOptions {
  uint64_t seed = 1;
  int threads = 0;
  bool progress = true;
};

// The exposures the capture will use (computed from the rig and the material by rendering the
// probe dot), so that a caller can describe the session before the images exist.
CaptureTruth PlanCapture(const SimulationPreset& preset, const RigRenderer& renderer,
                         uint64_t seed);

// Renders every capture of `plan` into `sink`, skipping those it already contains. Polls
// ThrowIfInterrupted between images.
void RunCapture(const RigRenderer& renderer, const CaptureTruth& plan, CaptureSink& sink,
                const CaptureOptions& options);

// The list of captures in the order they are made (session::CaptureOrder), with their exposures.
std::vector<CaptureId> CaptureList(const Rig& rig, const CaptureTruth& plan);

// What the camera sees in a capture, whatever its bracket and repeat: captures of one scene share
// its radiance image.
std::string SceneOf(const session::CaptureKey& key);

}  // namespace svbtdf
