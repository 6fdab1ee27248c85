#pragma once
// The device factory: the camera, display and operator of a capture, real or simulated, from the
// specs a user types (docs/capture.md):
//
//   camera   v4l2:/dev/videoN | libcamera:ID | gphoto2[:PORT] | sim:DIR (the simulation in DIR)
//   display  sdl[:INDEX] | sim
//
// A simulated camera can only look at the simulated display, so the two share one SimWorld.

#include <memory>
#include <string>

#include "svbtdf/acquire/camera.h"
#include "svbtdf/acquire/capture_session.h"
#include "svbtdf/acquire/display.h"
#include "svbtdf/acquire/sim_hardware.h"

namespace svbtdf::acquire {

struct LabRig {
  std::shared_ptr<SimWorld> world;  // set when any device is simulated
  std::unique_ptr<Camera> camera;
  std::unique_ptr<Display> display;
  std::unique_ptr<Operator> op;
};

// Who arranges the scenes: "prompt" asks on the console, "as-is" captures without asking, "skip"
// leaves operator captures missing; empty means "prompt" on a terminal, else "as-is". With a
// simulated camera the virtual lab arranges itself, whatever the mode.
//
// Throws Error(kInvalidInput) naming --camera or --display for a spec that names no device, and
// the drivers' errors when a device cannot be opened.
LabRig OpenLabRig(const std::string& camera_spec, const std::string& display_spec, const std::string& operator_mode = "");

}  // namespace svbtdf::acquire
