// render::BackgroundScene and EnvironmentScene: where the picture lies, what it emits, how
// directions map onto the environment, and the files they refuse.
#include "svbtdf/render/scene.h"

#include <gtest/gtest.h>

#include <fstream>

#include "svbtdf/common/error.h"
#include "expect_error.h"
#include "temp_folder.h"

namespace svbtdf::render {
namespace {
using model::Vec3;

TEST(BackgroundScene, TheCheckerboardLiesBehindTheSampleAndRepeats) {
  const BackgroundScene scene = BackgroundScene::Checkerboard(0.05, 0.01);
  // Squares of 1 cm from the tile's top-left corner (-1 cm, +1 cm): (-0.5, 0.5) cm is in the
  // top-left square (bright), (0.5, 0.5) cm in the top-right (dark), (0.5, -0.5) cm in the
  // bottom-right (bright again), and the pattern repeats every 2 cm.
  EXPECT_FLOAT_EQ(scene.RadianceAt(-0.005, 0.005)[0], 0.9f);
  EXPECT_FLOAT_EQ(scene.RadianceAt(0.005, 0.005)[0], 0.1f);
  EXPECT_FLOAT_EQ(scene.RadianceAt(0.005, -0.005)[0], 0.9f);
  EXPECT_FLOAT_EQ(scene.RadianceAt(0.025, 0.005)[0], 0.1f);  // the next tile
  // A ray from the camera side straight down hits the plane under its origin; one going up sees nothing.
  const Vec3 origin(-0.005, 0.005, 0.3);
  EXPECT_FLOAT_EQ(scene.Radiance(origin, Vec3(0, 0, -1))[1], 0.9f);
  EXPECT_EQ(scene.Radiance(origin, Vec3(0, 0, 1))[1], 0.0);
  // Slanted: from the sample's centre at 45 degrees toward +x the ray meets the plane at x = 5 cm.
  EXPECT_EQ(scene.Radiance(Vec3(0, 0.005, 0), Vec3(1, 0, -1).normalized()), scene.RadianceAt(0.05, 0.005));
  EXPECT_THROW(BackgroundScene::Checkerboard(-1, 0.01), common::Error);
}

TEST(BackgroundScene, APictureIsDecodedFromSrgbAndAnExrIsTakenAsIs) {
  const testing::TempFolder folder;
  common::FloatImage picture(4, 2, 3, 0.5f);
  common::WriteFloatImage(folder / "linear.exr", picture, false);
  const BackgroundScene linear = BackgroundScene::FromImage(folder / "linear.exr", 0.05, 0.04);
  EXPECT_NEAR(linear.RadianceAt(0.0, 0.0)[0], 0.5, 1e-6);
  common::WriteRgb8Png(folder / "grey.png", std::vector<uint8_t>(4 * 2 * 3, 188), 4, 2);
  const BackgroundScene srgb = BackgroundScene::FromImage(folder / "grey.png", 0.05, 0.04);
  EXPECT_NEAR(srgb.RadianceAt(0.001, 0.001)[0], 0.5029, 1e-3);  // sRGB 188/255 is linear 0.503
  std::ofstream(folder / "broken.png") << "not a png";
  try {
    BackgroundScene::FromImage(folder / "broken.png", 0.05, 0.04);
    FAIL() << "a broken picture was read";
  } catch (const common::Error& e) {
    EXPECT_NE(std::string(e.what()).find("broken.png"), std::string::npos) << e.what();
  }
}

TEST(EnvironmentScene, BehindTheSampleIsTheMapsCentreAndUpIsItsTopRow) {
  common::FloatImage map(8, 4, 3, 0.0f);
  for (int y = 0; y < 4; ++y) {
    for (int x = 0; x < 8; ++x) map.at(x, y, 0) = static_cast<float>(x), map.at(x, y, 1) = static_cast<float>(y);
  }
  const EnvironmentScene scene(map);
  const model::Rgb behind = scene.Radiance(Vec3::Zero(), Vec3(0, 0, -1));
  EXPECT_NEAR(behind[0], 3.5, 1e-9);  // u = 1/2: between columns 3 and 4
  EXPECT_NEAR(behind[1], 1.5, 1e-9);  // the horizon: between rows 1 and 2
  EXPECT_NEAR(scene.Radiance(Vec3::Zero(), Vec3(0, 1, 0))[1], 0.0, 1e-9);  // up: the top row (clamped)
  EXPECT_NEAR(scene.Radiance(Vec3::Zero(), Vec3(1, 0, 0))[0], 5.5, 1e-9);  // +x: u = 3/4
  const testing::TempFolder folder;
  common::WriteRgb8Png(folder / "env.png", std::vector<uint8_t>(8 * 4 * 3, 10), 8, 4);
  EXPECT_THROW(EnvironmentScene::FromImage(folder / "env.png"), common::Error);
}

TEST(MakeScene, BuildsTheNamedSceneAndRefusesUnknownOnesNamingTheOption) {
  SceneOptions options;
  const std::unique_ptr<Scene> checkerboard = MakeScene(options, 0.08);
  const BackgroundScene expected = BackgroundScene::Checkerboard(options.background_distance_m, options.checker_size_m);
  const model::Vec3 origin(0.001, 0.002, 0.0), direction = model::Vec3(0.1, -0.2, -1.0).normalized();
  EXPECT_EQ(checkerboard->Radiance(origin, direction), expected.Radiance(origin, direction));
  options.scene = "studio";
  svbtdf::testing::ExpectError(common::ErrorKind::kInvalidInput, "--scene", [&] { MakeScene(options, 0.08); });
  options.scene = "environment";
  svbtdf::testing::ExpectError(common::ErrorKind::kInvalidInput, "--environment", [&] { MakeScene(options, 0.08); });
}

}  // namespace
}  // namespace svbtdf::render
