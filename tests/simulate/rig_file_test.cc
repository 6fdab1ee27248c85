// A lab's rig file (docs/capture.md, "The rig file"): what it gives replaces the preset's
// settings and nothing else; a wrong field or an impossible rig is one error naming the file and
// the field; no bytes make it crash.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "svbtdf/common/error.h"
#include "svbtdf/simulate/presets.h"
#include "svbtdf/simulate/rig_file.h"

namespace svbtdf::simulate {
namespace {

constexpr const char* kLabRig = R"({
  "format": "svbtdf-rig", "version": 1, "preset": "demo",
  "camera": { "fx": 5000, "distance_mm": 1100, "theta_deg": 40, "frame_time_s": 0.05,
              "control_delay_frames": 4, "bit_depth": 14 },
  "monitor": { "distance_mm": 45, "pixel_pitch_mm": 0.2, "emission": "lambertian", "polarisation": "linear:135" },
  "sample": { "width_mm": 70, "eta": 1.45 }
})";

TEST(RigFile, GivenSettingsReplaceThePresetsAndTheRestStay) {
  const RigFile file = ParseRigFile(kLabRig, "lab.json");
  const RigConfig preset = MakePreset("demo").rig;
  EXPECT_EQ(file.preset, "demo");
  EXPECT_DOUBLE_EQ(file.rig.intrinsics.fx, 5000.0);
  EXPECT_DOUBLE_EQ(file.rig.intrinsics.fy, 5000.0);  // fx alone: square pixels
  EXPECT_DOUBLE_EQ(file.rig.intrinsics.cx, preset.intrinsics.cx);
  EXPECT_NEAR(file.rig.pose.Centre().norm(), 1.1, 1e-12);
  EXPECT_NEAR(std::acos(file.rig.pose.Centre().normalized().z()) * 180 / model::kPi, 40.0, 1e-9);
  EXPECT_DOUBLE_EQ(file.frame_time_s, 0.05);
  EXPECT_EQ(file.control_delay_frames, 4);
  EXPECT_EQ(file.rig.sensor.bit_depth, 14);
  EXPECT_DOUBLE_EQ(file.rig.monitor.distance, 0.045);
  EXPECT_DOUBLE_EQ(file.rig.monitor.pixel_pitch, 0.0002);
  EXPECT_EQ(file.rig.monitor.emission.kind, "lambertian");
  EXPECT_EQ(file.rig.monitor.polarisation.ToString(), "linear:135");
  EXPECT_DOUBLE_EQ(file.rig.monitor.width, preset.monitor.width);
  EXPECT_DOUBLE_EQ(file.rig.sample.width, 0.07);
  EXPECT_EQ(file.rig.sample.texels_x, preset.sample.texels_x);
  EXPECT_DOUBLE_EQ(file.eta, 1.45);
  EXPECT_EQ(file.rig.window.sensor_width, preset.window.sensor_width);

  const RigFile bare = ParseRigFile(R"({"format": "svbtdf-rig", "version": 1, "preset": "tiny"})", "bare.json");
  EXPECT_DOUBLE_EQ(bare.rig.intrinsics.fx, MakePreset("tiny").rig.intrinsics.fx);
  EXPECT_DOUBLE_EQ(bare.eta, MakePreset("tiny").eta);
  EXPECT_FALSE(bare.rig.monitor.polarisation.linear());
}

std::string ErrorOf(const std::string& text) {
  try {
    ParseRigFile(text, "lab.json");
  } catch (const common::Error& e) {
    EXPECT_EQ(e.subject(), "lab.json") << e.what();
    return e.what();
  }
  ADD_FAILURE() << "accepted: " << text;
  return {};
}

TEST(RigFile, AWrongFieldOrAnImpossibleRigIsOneErrorNamingFileAndField) {
  const std::string head = R"({"format": "svbtdf-rig", "version": 1, )";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {head + R"("camera": {"focal": 5000}})", "camera.focal"},
      {head + R"("camera": {"fx": "big"}})", "camera.fx"},
      {head + R"("monitor": {"distance_mm": -3}})", "monitor.distance_mm"},
      {head + R"("monitor": {"emission": "laser"}})", "monitor.emission"},
      {head + R"("monitor": {"polarisation": "linear:up"}})", "monitor.polarisation"},
      {head + R"("sample": {"texels_x": 2.5}})", "sample.texels_x"},
      {head + R"("preset": "huge"})", "preset"},
      {R"({"format": "svbtdf-rig", "version": 7})", "version 7"},
      {R"({"format": "a rig", "version": 1})", "format"},
      // The sample no longer fits the image: the whole rig is checked, naming the file.
      {head + R"("camera": {"fx": 90000}})", "not in view"},
      {head + R"("camera": {"distortion": [1, 2, 3]}})", "camera.distortion"},
  };
  for (const auto& [text, expected] : cases) {
    const std::string message = ErrorOf(text);
    EXPECT_NE(message.find(expected), std::string::npos) << text << "\n -> " << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
}

TEST(RigFile, TruncatedFilesNeverCrash) {
  const std::string text = kLabRig;
  for (size_t n = 0; n < text.size(); ++n) {
    try {
      ParseRigFile(text.substr(0, n), "cut.json");
    } catch (const common::Error&) {
    }
  }
}

}  // namespace
}  // namespace svbtdf::simulate
