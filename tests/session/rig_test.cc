// The typed rig description of session.json: every field round-trips, unknown keys are kept,
// unset fields are left out, and a field of the wrong type is an error naming the file and key.

#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

#include "svbtdf/common/error.h"
#include "svbtdf/session/rig.h"

namespace svbtdf::session {
namespace {

using nlohmann::json;

RigDescription Full() {
  RigDescription d;
  d.camera = {"v4l2:/dev/video0", "lab cam", 640, 480, 3, 12, "srgb", {1280, 1024, 320, 272}};
  d.monitor.id = "sdl:0";
  d.monitor.width_px = 1920;
  d.monitor.height_px = 1080;
  d.monitor.gamma = 2.2;
  d.monitor.pixel_pitch_m = 0.000311;
  d.monitor.distance_m = 0.04;
  d.monitor.orientation_deg = 90;
  d.monitor.black_level = 0.001;
  d.monitor.emission = "lcd";
  d.dots.cols = 2;
  d.dots.rows = 1;
  d.dots.radius_px = 4;
  d.dots.positions_px = {{100.5, 200}, {140, 200}};
  d.dots.fiducials = std::vector<int>{1};
  d.board = {"chessboard:9x6:25", 12};
  d.sample_plane_board = {"chessboard:12x12:6", 0};
  d.sample = {0.08, 0.06, 32, 24, 1.5};
  d.exposures_s = {0.01, 0.16};
  d.acquisition_plan = {{"format", "svbtdf-capture-plan"}};
  d.simulated = {{"preset", "tiny"}};
  d.others = {{"operator", "Ana"}};
  return d;
}

TEST(RigDescription, EveryFieldRoundTripsAndUnknownKeysAreKept) {
  const json written = ToJson(Full());
  const RigDescription d = ParseRigDescription(written, "session.json");
  EXPECT_EQ(ToJson(d), written);
  EXPECT_EQ(d.camera.sensor, (SensorWindow{1280, 1024, 320, 272}));
  EXPECT_EQ(d.camera.response, "srgb");
  EXPECT_DOUBLE_EQ(d.monitor.black_level, 0.001);
  EXPECT_EQ(d.dots.positions_px[0], std::make_pair(100.5, 200.0));
  ASSERT_TRUE(d.dots.fiducials.has_value());
  EXPECT_EQ(*d.dots.fiducials, std::vector<int>{1});
  EXPECT_EQ(d.sample.texels_y, 24);
  EXPECT_EQ(d.others.at("operator"), "Ana");
  EXPECT_EQ(written.at("camera").at("sensor").at("window_offset"), json({320, 272}));
}

TEST(RigDescription, UnsetFieldsAreLeftOutAndReadBackUnset) {
  RigDescription d;
  d.camera.id = "sim";
  const json written = ToJson(d);
  EXPECT_EQ(written, json({{"camera", {{"id", "sim"}}}}));
  const RigDescription back = ParseRigDescription(json::object(), "session.json");
  EXPECT_TRUE(back.camera.sensor.whole_sensor());
  EXPECT_TRUE(std::isnan(back.monitor.orientation_deg));
  EXPECT_FALSE(back.dots.fiducials.has_value());
  EXPECT_TRUE(back.acquisition_plan.is_null());
}

TEST(RigDescription, AFieldOfTheWrongTypeIsNamedWithItsFile) {
  const auto message = [](const json& rig) {
    try {
      ParseRigDescription(rig, "/lab/s1/session.json");
    } catch (const common::Error& e) {
      return std::string(e.what());
    }
    return std::string("not refused");
  };
  std::string m = message({{"camera", {{"width", "640"}}}});
  EXPECT_NE(m.find("/lab/s1/session.json"), std::string::npos) << m;
  EXPECT_NE(m.find("rig.camera.width"), std::string::npos) << m;
  m = message({{"dots", {{"positions_px", {{1, 2}, {3}}}}}});
  EXPECT_NE(m.find("rig.dots.positions_px"), std::string::npos) << m;
  m = message({{"camera", {{"sensor", {{"width", 100}, {"height", 100}, {"window_offset", {1}}}}}}});
  EXPECT_NE(m.find("rig.camera.sensor"), std::string::npos) << m;
  m = message({{"monitor", 3}});
  EXPECT_NE(m.find("rig.monitor must be an object"), std::string::npos) << m;
  EXPECT_NE(message(json::array()).find("rig must be an object"), std::string::npos);
}

// Issue 15: nonsense was accepted (eta -1.5 or 1e308, a camera -240 or 1e12 pixels wide, a
// sample 0 m wide, a bit depth of 100) and failed later, unnamed. Each is refused by field.
TEST(RigDescription, PhysicallyImpossibleValuesAreRefusedNamingTheField) {
  const std::vector<std::pair<json, std::string>> cases = {
      {{{"sample", {{"eta", -1.5}}}}, "rig.sample.eta"},
      {{{"sample", {{"eta", 1e308}}}}, "rig.sample.eta"},
      {{{"camera", {{"width", -240}}}}, "rig.camera.width"},
      {{{"camera", {{"width", 1e12}}}}, "rig.camera.width"},
      {{{"camera", {{"width", 640.5}}}}, "rig.camera.width"},
      {{{"camera", {{"bit_depth", 100}}}}, "rig.camera.bit_depth"},
      {{{"camera", {{"bit_depth", -5}}}}, "rig.camera.bit_depth"},
      {{{"sample", {{"width_m", 0.0}}}}, "rig.sample.width_m"},
      {{{"sample", {{"texels_x", 100000}}}}, "rig.sample.texels_x"},
      {{{"monitor", {{"gamma", -2.2}}}}, "rig.monitor.gamma"},
      {{{"exposures_s", {0.01, -1.0}}}, "rig.exposures_s"},
  };
  for (const auto& [rig, field] : cases) {
    try {
      ParseRigDescription(rig, "SESSION/session.json");
      ADD_FAILURE() << rig.dump() << " was accepted";
    } catch (const common::Error& e) {
      EXPECT_EQ(e.kind(), common::ErrorKind::kFormat);
      EXPECT_NE(std::string(e.what()).find("SESSION/session.json"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  }
  EXPECT_NO_THROW(ParseRigDescription(ToJson(Full()), "session.json"));
}

}  // namespace
}  // namespace svbtdf::session
