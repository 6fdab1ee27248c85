// Blender (Debian's 3.4, installed by scripts/install-deps.sh) imports an export whose roughness
// changes across the sample and renders it with Cycles on the CPU in front of a checkerboard
// (tools/blender/render_export.py): the imported material carries roughness, transmission and
// IOR, and the picture is blurred more where the exported roughness is higher. Label `blender`
// (in the default run; skip it by hand with `ctest -LE blender`). About 5 seconds.

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "../cli/run_command.h"
#include "small_material.h"
#include "svbtdf/common/json.h"
#include "svbtdf/fit/material.h"
#include "temp_folder.h"

namespace svbtdf {
namespace {
namespace fs = std::filesystem;

TEST(GltfInBlender, CyclesBlursMoreWhereTheExportedRoughnessIsHigher) {
  ASSERT_EQ(std::system("command -v blender > /dev/null"), 0) << "blender is missing: run scripts/install-deps.sh";
  const testing::TempFolder folder;
  // Six regions, alpha 0.02 to 0.5 (glTF roughness 0.14 to 0.71), in an order that is not the
  // regions' own so that a mirrored or transposed texture would break the correlation.
  fit::WriteMaterial(folder / "regions", RegionsMaterial(3, 2, 6, {0.1, 0.02, 0.35, 0.5, 0.05, 0.2}));
  const auto exported = testing::RunSvbtdf("export " + (folder / "regions").string() + " --gltf " +
                                           (folder / "out").string() + " --threads 1");
  ASSERT_EQ(exported.exit_code, 0) << exported.output;
  const fs::path script = fs::path(SVBTDF_SOURCE_DIR) / "tools" / "blender" / "render_export.py";
  const std::string command = "blender -b --factory-startup --python " + script.string() + " -- --gltf " +
                              (folder / "out" / "regions.gltf").string() + " --png " + (folder / "cycles.png").string() +
                              " --json " + (folder / "blender.json").string() + " --regions 3 2 > " +
                              (folder / "blender.log").string() + " 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << "blender failed; see " << (folder / "blender.log");
  const nlohmann::json result = common::ReadJsonFile(folder / "blender.json");
  const nlohmann::json& material = result["material"];
  EXPECT_TRUE(material["roughness"]["linked"].get<bool>()) << material.dump();     // the texture's G channel
  EXPECT_TRUE(material["transmission"]["linked"].get<bool>()) << material.dump();  // the transmission texture
  EXPECT_NEAR(material["ior"]["value"].get<double>(), 1.5, 1e-6) << material.dump();
  EXPECT_GT(result["spearman_roughness_blur"].get<double>(), 0.8) << result["regions"].dump(2);
  // And the effect is large: the sharpest region keeps far more of the checkerboard than the roughest.
  double sharpest = 0, roughest = 0;
  for (const auto& region : result["regions"]) {
    const double roughness = region["roughness"].get<double>();
    if (roughness < 0.2) sharpest = region["contrast"].get<double>();
    if (roughness > 0.65) roughest = region["contrast"].get<double>();
  }
  EXPECT_GT(sharpest, 3 * roughest) << result["regions"].dump(2);
  RecordProperty("spearman", std::to_string(result["spearman_roughness_blur"].get<double>()));
  RecordProperty("blender_seconds", std::to_string(result["seconds"].get<double>()));
}

}  // namespace
}  // namespace svbtdf
