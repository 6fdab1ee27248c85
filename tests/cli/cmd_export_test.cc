// `svbtdf export` (issue 17's command-line contract): an export prints its figures and writes
// the glTF with its files; bad input gets one line naming the file and exit 2. And `svbtdf render
// --parametric` renders the lobes the export carries, close to the tabulated material's picture.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "run_command.h"
#include "small_material.h"
#include "svbtdf/common/json.h"
#include "svbtdf/fit/material.h"
#include "temp_folder.h"

namespace svbtdf {
namespace {
namespace fs = std::filesystem;
using testing::RunSvbtdf;

TEST(ExportCommand, WritesTheGltfAndPrintsTheLobeFitsError) {
  const testing::TempFolder folder;
  fit::WriteMaterial(folder / "sheet", RegionsMaterial(2, 2, 4, {0.05, 0.1, 0.2, 0.4}));
  const auto result = RunSvbtdf("export " + (folder / "sheet").string() + "/ --gltf " + (folder / "out").string());
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("GGX lobe fit relative error: median"), std::string::npos) << result.output;
  // The name comes from the folder, however its path was typed.
  EXPECT_TRUE(fs::is_regular_file(folder / "out" / "sheet.gltf"));
  EXPECT_TRUE(fs::is_regular_file(folder / "out" / "sheet.bin"));
  const nlohmann::json summary = common::ReadJsonFile(folder / "out" / "sheet.export.json");
  EXPECT_EQ(summary["texels"].get<int>(), 64);
  EXPECT_GT(summary["lobe_fit"]["seconds"].get<double>(), 0.0);
  const auto named = RunSvbtdf("export " + (folder / "sheet").string() + " --name other --gltf " + (folder / "out").string());
  ASSERT_EQ(named.exit_code, 0) << named.output;
  EXPECT_TRUE(fs::is_regular_file(folder / "out" / "other.gltf"));
}

TEST(ExportCommand, BadInputGetsOneLineNamingTheFile) {
  const testing::TempFolder folder;
  const std::string out = " --gltf " + (folder / "out").string();
  const auto not_material = RunSvbtdf("export " + folder.path().string() + out);
  EXPECT_EQ(not_material.exit_code, 2) << not_material.output;
  EXPECT_NE(not_material.output.find("material.json"), std::string::npos) << not_material.output;

  fit::WriteMaterial(folder / "damaged", SmallMaterial());
  std::ofstream(folder / "damaged" / "material.json") << "{\"format\": \"svbtdf-material\", \"version\": ";
  const auto damaged = RunSvbtdf("export " + (folder / "damaged").string() + out);
  EXPECT_EQ(damaged.exit_code, 2) << damaged.output;
  EXPECT_NE(damaged.output.find("material.json"), std::string::npos) << damaged.output;

  fit::WriteMaterial(folder / "unsized", SmallMaterial());
  const auto unsized = RunSvbtdf("export " + (folder / "unsized").string() + out);
  EXPECT_EQ(unsized.exit_code, 2) << unsized.output;
  EXPECT_NE(unsized.output.find("sample"), std::string::npos) << unsized.output;
  for (const auto* result : {&not_material, &damaged, &unsized}) {
    EXPECT_EQ(std::count(result->output.begin(), result->output.end(), '\n'), 1) << result->output;
  }
}

TEST(RenderCommand, ParametricRendersTheExportsLobesCloseToTheTables) {
  const testing::TempFolder folder;
  fit::WriteMaterial(folder / "sheet", RegionsMaterial(2, 1, 4, {0.1, 0.3}, /*anisotropy=*/0.5, 0.01, 32));
  const std::string common = (folder / "sheet").string() + " --resolution 48 24 --spp 32 --view-deg 20 30 ";
  const auto tables = RunSvbtdf("render " + common + "--out " + (folder / "tables.exr").string());
  ASSERT_EQ(tables.exit_code, 0) << tables.output;
  // The Monte Carlo noise between two renders of the tables, and the lobes against the tables,
  // both with another seed than the reference's.
  const std::string reference = " --compare-to " + (folder / "tables.exr").string() + " --seed 9 --json ";
  const auto noise = RunSvbtdf("render " + common + "--out " + (folder / "noise.exr").string() + reference +
                               (folder / "noise.json").string());
  ASSERT_EQ(noise.exit_code, 0) << noise.output;
  const auto lobes = RunSvbtdf("render " + common + "--parametric --out " + (folder / "lobes.exr").string() + reference +
                               (folder / "lobes.json").string());
  ASSERT_EQ(lobes.exit_code, 0) << lobes.output;
  EXPECT_NE(lobes.output.find("GGX lobe per texel"), std::string::npos) << lobes.output;
  // The lobes are the tables' own (GGX at cell centres): the pictures differ by noise, and little more.
  const double noise_error = common::ReadJsonFile(folder / "noise.json")["relative_rmse"].get<double>();
  const double lobe_error = common::ReadJsonFile(folder / "lobes.json")["relative_rmse"].get<double>();
  EXPECT_LT(lobe_error, 1.2 * noise_error) << "noise " << noise_error;
  const auto truth = RunSvbtdf("render " + folder.path().string() + " --parametric --out " + (folder / "x.exr").string());
  EXPECT_EQ(truth.exit_code, 2) << truth.output;
}

}  // namespace
}  // namespace svbtdf
