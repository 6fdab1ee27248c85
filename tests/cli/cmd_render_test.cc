// `svbtdf render` (issue 16's command-line contract): a material renders to EXR and PNG with the
// figures it prints, and bad input gets one line naming what is wrong.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "run_command.h"
#include "small_material.h"
#include "svbtdf/common/image_io.h"
#include "svbtdf/common/json.h"
#include "svbtdf/fit/material.h"
#include "temp_folder.h"

namespace svbtdf {
namespace {
namespace fs = std::filesystem;
using testing::RunSvbtdf;

TEST(RenderCommand, WritesAnExrAndAPngAndComparesWithAReference) {
  const testing::TempFolder folder;
  fit::Material material = SmallMaterial();
  material.width_m = 0.03;
  material.height_m = 0.02;
  fit::WriteMaterial(folder / "material", material);
  const std::string common = (folder / "material").string() + " --resolution 40 24 --spp 4 --view-deg 20 45 ";
  const auto first = RunSvbtdf("render " + common + "--out " + (folder / "a.exr").string() + " --png " +
                               (folder / "a.png").string());
  ASSERT_EQ(first.exit_code, 0) << first.output;
  EXPECT_NE(first.output.find("40x24 at 4 spp"), std::string::npos) << first.output;
  const common::FloatImage image = common::ReadFloatImage(folder / "a.exr");
  EXPECT_EQ(image.width, 40);
  EXPECT_EQ(image.height, 24);
  EXPECT_EQ(image.channels, 3);
  EXPECT_TRUE(fs::is_regular_file(folder / "a.png"));
  // The same command renders the same image; another seed is compared against it.
  const auto again = RunSvbtdf("render " + common + "--seed 7 --out " + (folder / "b.exr").string() + " --compare-to " +
                               (folder / "a.exr").string() + " --json " + (folder / "b.json").string());
  ASSERT_EQ(again.exit_code, 0) << again.output;
  const nlohmann::json metrics = common::ReadJsonFile(folder / "b.json");
  EXPECT_GT(metrics["relative_rmse"].get<double>(), 0.0);
  EXPECT_LT(metrics["relative_rmse"].get<double>(), 0.5);
  EXPECT_GT(metrics["ssim"].get<double>(), 0.3);
}

TEST(RenderCommand, BadInputGetsOneLineNamingIt) {
  const testing::TempFolder folder;
  fit::WriteMaterial(folder / "unsized", SmallMaterial());
  const std::string out = " --out " + (folder / "x.exr").string();
  const auto behind = RunSvbtdf("render " + (folder / "unsized").string() + out + " --view-deg 100 0 --sample-size 0.03 0.02");
  EXPECT_EQ(behind.exit_code, 2) << behind.output;
  EXPECT_NE(behind.output.find("--view-deg"), std::string::npos) << behind.output;
  const auto unsized = RunSvbtdf("render " + (folder / "unsized").string() + out);
  EXPECT_NE(unsized.exit_code, 0);
  EXPECT_NE(unsized.output.find("--sample-size"), std::string::npos) << unsized.output;
  const auto not_material = RunSvbtdf("render " + folder.path().string() + out);
  EXPECT_NE(not_material.exit_code, 0);
  EXPECT_NE(not_material.output.find("material.json"), std::string::npos) << not_material.output;
  const auto bad_background = RunSvbtdf("render " + (folder / "unsized").string() + out +
                                        " --sample-size 0.03 0.02 --background " + (folder / "none.png").string());
  EXPECT_NE(bad_background.exit_code, 0);
  EXPECT_NE(bad_background.output.find("none.png"), std::string::npos) << bad_background.output;
  const auto no_environment = RunSvbtdf("render " + (folder / "unsized").string() + out + " --sample-size 0.03 0.02 --scene environment");
  EXPECT_EQ(no_environment.exit_code, 2) << no_environment.output;
  EXPECT_NE(no_environment.output.find("--environment"), std::string::npos) << no_environment.output;
  EXPECT_FALSE(fs::exists(folder / "x.exr"));
}

}  // namespace
}  // namespace svbtdf
