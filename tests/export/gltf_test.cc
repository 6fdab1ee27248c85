// The glTF writer: the per-texel mapping's algebra (KHR_materials_anisotropy's roughnesses, the
// transmitted energy split), and the files an export writes and how they refer to each other.

#include "svbtdf/export/gltf.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>

#include "small_material.h"
#include "svbtdf/common/image_io.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/json.h"
#include "temp_folder.h"

namespace svbtdf::exporter {
namespace {
namespace fs = std::filesystem;

// KHR_materials_anisotropy's roughness along the direction: mix(alpha, 1, strength^2).
double AlphaAlongDirection(const GltfTexel& t) {
  const double alpha = t.roughness * t.roughness;
  return alpha + (1.0 - alpha) * t.anisotropy_strength * t.anisotropy_strength;
}

TEST(MapTexel, AnIsotropicLobeHasNoAnisotropy) {
  const GltfTexel t = MapTexel({0.09, 0.09, 0.7}, {0.8, 0.8, 0.8}, {0, 0, 0});
  EXPECT_NEAR(t.roughness, 0.3, 1e-12);
  EXPECT_NEAR(t.anisotropy_strength, 0.0, 1e-12);
  EXPECT_FALSE(t.clamped);
}

TEST(MapTexel, TheExtensionGivesBackBothAlphasAndTheWiderAxis) {
  const GltfTexel t = MapTexel({0.5, 0.2, 0.4}, {0.8, 0.8, 0.8}, {0, 0, 0});
  EXPECT_NEAR(t.roughness * t.roughness, 0.2, 1e-12);
  EXPECT_NEAR(AlphaAlongDirection(t), 0.5, 1e-12);
  EXPECT_NEAR(std::atan2(t.direction_y, t.direction_x), 0.4, 1e-12);
  // The same lobe written with its axes the other way round.
  const GltfTexel swapped = MapTexel({0.2, 0.5, 0.4 - std::numbers::pi / 2}, {0.8, 0.8, 0.8}, {0, 0, 0});
  EXPECT_NEAR(swapped.roughness, t.roughness, 1e-12);
  EXPECT_NEAR(swapped.anisotropy_strength, t.anisotropy_strength, 1e-12);
  EXPECT_NEAR(swapped.direction_x, t.direction_x, 1e-12);
  EXPECT_NEAR(swapped.direction_y, t.direction_y, 1e-12);
}

TEST(MapTexel, AlphaBeyondGltfsRangeIsClampedAndSaid) {
  const GltfTexel t = MapTexel({1.7, 0.3, 0.0}, {0.8, 0.8, 0.8}, {0, 0, 0});
  EXPECT_TRUE(t.clamped);
  EXPECT_NEAR(AlphaAlongDirection(t), 1.0, 1e-12);
}

TEST(MapTexel, SplitsTheTransmittedEnergyBetweenTheSpecularAndDiffuseBtdfs) {
  const std::array<double, 3> k_s = {0.6, 0.5, 0.4}, rho_d = {0.03, 0.04, 0.05};
  const GltfTexel t = MapTexel({0.1, 0.1, 0}, k_s, rho_d);
  ASSERT_FALSE(t.clamped);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(t.transmission * t.base_color[c], k_s[c], 1e-12);
    EXPECT_NEAR((1 - t.transmission) * t.diffuse_transmission_color[c], std::numbers::pi * rho_d[c], 1e-12);
  }
}

TEST(WriteGltf, WritesAQuadOfTheSamplesSizeAndEveryTextureItNames) {
  const testing::TempFolder folder;
  const fit::Material material = RegionsMaterial(2, 1, 4, {0.1, 0.4});
  const MaterialLobes lobes = FitMaterialLobes(material, 1);
  const GltfFiles files = WriteGltf(material, lobes, folder / "out", "sheet");
  EXPECT_EQ(files.gltf, folder / "out" / "sheet.gltf");
  const nlohmann::json gltf = common::ReadJsonFile(files.gltf);
  for (const char* extension : {"KHR_materials_transmission", "KHR_materials_volume", "KHR_materials_ior",
                                "KHR_materials_anisotropy", "KHR_materials_diffuse_transmission"}) {
    EXPECT_TRUE(gltf["materials"][0]["extensions"].contains(extension)) << extension;
  }
  EXPECT_EQ(gltf["materials"][0]["extensions"]["KHR_materials_ior"]["ior"].get<double>(), 1.5);
  EXPECT_EQ(gltf["materials"][0]["extensions"]["KHR_materials_volume"]["thicknessFactor"].get<double>(), 0.0);
  const nlohmann::json& position = gltf["accessors"][gltf["meshes"][0]["primitives"][0]["attributes"]["POSITION"].get<int>()];
  EXPECT_NEAR(position["max"][0].get<double>() - position["min"][0].get<double>(), material.width_m, 1e-7);
  EXPECT_NEAR(position["max"][1].get<double>() - position["min"][1].get<double>(), material.height_m, 1e-7);
  EXPECT_EQ(fs::file_size(folder / "out" / gltf["buffers"][0]["uri"].get<std::string>()),
            gltf["buffers"][0]["byteLength"].get<size_t>());
  for (const auto& image : gltf["images"]) {
    const common::FloatImage png = common::ReadFloatImage(folder / "out" / image["uri"].get<std::string>());
    EXPECT_EQ(png.width, material.width);
    EXPECT_EQ(png.height, material.height);
  }
  // The rougher region (right) is rougher in the metallic-roughness texture's G channel.
  const common::FloatImage roughness = common::ReadFloatImage(folder / "out" / "sheet_metallic_roughness.png");
  EXPECT_NEAR(roughness.at(1, 1, 1), std::sqrt(0.1), 0.02);
  EXPECT_NEAR(roughness.at(6, 1, 1), std::sqrt(0.4), 0.02);
  const nlohmann::json summary = common::ReadJsonFile(files.summary);
  EXPECT_LT(summary["lobe_fit"]["relative_error"]["max"].get<double>(), 0.05);
  EXPECT_TRUE(fs::is_regular_file(folder / "out" / "sheet_lobe_error.exr"));
}

// The summary names what glTF cannot hold; the internal-reflection term only when the material has it.
TEST(WriteGltf, TheSummaryNamesTheInternalReflectionTermItDrops) {
  const testing::TempFolder folder;
  fit::Material material = RegionsMaterial(2, 1, 4, {0.1, 0.4});
  const auto dropped = [&](const char* name) {
    const GltfFiles files = WriteGltf(material, FitMaterialLobes(material, 1), folder / name, name);
    const std::string not_carried = common::ReadJsonFile(files.summary)["not_carried"].dump();
    return not_carried.find("inside the slab") != std::string::npos;
  };
  EXPECT_FALSE(dropped("plain"));
  material.internal_reflection = true;
  EXPECT_TRUE(dropped("with_term"));
}

TEST(WriteGltf, RefusesAMaterialWithoutASize) {
  const testing::TempFolder folder;
  const fit::Material material = SmallMaterial();
  EXPECT_THROW(WriteGltf(material, FitMaterialLobes(material, 1), folder / "out", "small"), common::Error);
}

}  // namespace
}  // namespace svbtdf::exporter
