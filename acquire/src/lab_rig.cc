#include "svbtdf/acquire/lab_rig.h"

#include <unistd.h>

#include <iostream>
#include <utility>

#include "svbtdf/acquire/gphoto2_camera.h"
#include "svbtdf/acquire/libcamera_camera.h"
#include "svbtdf/acquire/sdl_display.h"
#include "svbtdf/acquire/v4l2_camera.h"
#include "svbtdf/common/error.h"

namespace svbtdf::acquire {
namespace {

// "kind:target" -> {kind, target}; no colon: {spec, ""}.
std::pair<std::string, std::string> SplitSpec(const std::string& spec) {
  const size_t colon = spec.find(':');
  if (colon == std::string::npos) return {spec, ""};
  return {spec.substr(0, colon), spec.substr(colon + 1)};
}

std::unique_ptr<Camera> OpenCamera(const std::string& spec, LabRig& rig) {
  const auto [kind, target] = SplitSpec(spec);
  if (kind == "v4l2" && !target.empty()) return OpenV4l2Camera(target);
  if (kind == "libcamera" && !target.empty()) return OpenLibcameraCamera(target);
  if (kind == "gphoto2") return OpenGphoto2Camera(target);
  if (kind == "sim" && !target.empty()) {
    auto setup = LoadSimulation(target);
    rig.world = std::make_shared<SimWorld>();
    rig.display = std::make_unique<SimDisplay>(rig.world, SimDisplayInfo(*setup));
    return std::make_unique<SimCamera>(rig.world, setup, spec);
  }
  common::ThrowInvalidInput("--camera", "'" + spec + "' is not a camera",
                    "use v4l2:/dev/videoN, libcamera:ID, gphoto2[:PORT] or sim:DIR (see `svbtdf devices`)");
}

void OpenDisplay(const std::string& spec, LabRig& rig) {
  const auto [kind, target] = SplitSpec(spec);
  if (rig.world) {  // a simulated camera can only look at the simulated monitor
    if (spec != "sim") common::ThrowInvalidInput("--display", "a sim: camera needs --display sim, got '" + spec + "'");
    return;
  }
  if (spec == "sim") {
    rig.world = std::make_shared<SimWorld>();
    DisplayInfo info;
    info.id = "sim";
    info.width_px = 1920;
    info.height_px = 1080;
    rig.display = std::make_unique<SimDisplay>(rig.world, info);
    return;
  }
  if (kind == "sdl") {
    int index = 0;
    try {
      index = target.empty() ? 0 : std::stoi(target);
    } catch (const std::exception&) {
      common::ThrowInvalidInput("--display", "'" + spec + "': the display index must be a number");
    }
    rig.display = OpenSdlDisplay(index);
    return;
  }
  common::ThrowInvalidInput("--display", "'" + spec + "' is not a display", "use sdl[:INDEX] or sim");
}

std::unique_ptr<Operator> MakeOperator(const std::string& mode_asked, const LabRig& rig) {
  if (rig.world && dynamic_cast<SimCamera*>(rig.camera.get())) {
    return std::make_unique<SimOperator>(rig.world);  // the virtual lab arranges itself
  }
  const std::string mode = !mode_asked.empty() ? mode_asked : (::isatty(STDIN_FILENO) ? "prompt" : "as-is");
  if (mode == "prompt") return std::make_unique<ConsoleOperator>(std::cin, std::cerr);
  if (mode == "skip") return std::make_unique<UnattendedOperator>(UnattendedPolicy::kSkip);
  if (mode == "as-is") return std::make_unique<UnattendedOperator>(UnattendedPolicy::kAsIs);
  common::ThrowInvalidInput("--calibration", "'" + mode + "' is not an operator mode", "use prompt, as-is or skip");
}

}  // namespace

LabRig OpenLabRig(const std::string& camera_spec, const std::string& display_spec, const std::string& operator_mode) {
  LabRig rig;
  rig.camera = OpenCamera(camera_spec, rig);
  OpenDisplay(display_spec, rig);
  rig.op = MakeOperator(operator_mode, rig);
  return rig;
}

}  // namespace svbtdf::acquire
