#pragma once
// A lab's own rig described in a file (docs/capture.md, "The rig file", version 1): the camera
// (lens, pose, sensor, frame time), the monitor and the sample, starting from a simulator preset
// whose every setting the file may replace. `svbtdf plan` reads it to predict a capture, and
// `svbtdf simulate --rig` renders a capture on it.

#include <filesystem>
#include <string>

#include "svbtdf/simulate/rig.h"

namespace svbtdf::simulate {

inline constexpr const char* kRigFileFormat = "svbtdf-rig";
inline constexpr int kRigFileVersion = 1;

struct RigFile {
  std::string preset = "demo";  // the preset the file starts from (its rig and its material)
  RigConfig rig;
  double eta = 1.5;             // the sample's relative index of refraction (the preset's unless given)
  // What the planner needs of the camera beyond the simulator: its measured frame time (one frame
  // at the video rate, or a still camera's shot-to-shot time) and how many frames a new exposure
  // takes to apply (V4L2 and libcamera apply controls a few frames late; the drivers discard
  // frames until the metadata shows the new exposure).
  double frame_time_s = 1.0 / 30.0;
  int control_delay_frames = 3;
};

// The rig of a preset with the planner's default camera timing.
RigFile RigFileOfPreset(const std::string& preset);

// Parses a rig file. Every problem, a wrong field or an impossible rig (the sample out of view,
// the monitor in front of the sample ...), is one svbtdf::Error(kFormat) naming `source` and the
// field. Never anything else, whatever the bytes.
RigFile ParseRigFile(const std::string& text, const std::string& source);
RigFile ReadRigFile(const std::filesystem::path& path);

}  // namespace svbtdf::simulate
