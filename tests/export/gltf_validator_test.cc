// The Khronos glTF-Validator (tools/gltf: the npm package gltf-validator, pinned, installed by
// scripts/install-deps.sh) on the exports `svbtdf export` writes: 0 errors and 0 warnings.
// Label `interop`; part of the default run.

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

const fs::path kValidator = fs::path(SVBTDF_SOURCE_DIR) / "tools" / "gltf" / "validate.js";

// Runs the validator on `gltf`; returns its report (the test fails when it cannot run).
nlohmann::json Validate(const fs::path& gltf, const fs::path& report) {
  const fs::path package = kValidator.parent_path() / "node_modules" / "gltf-validator";
  EXPECT_TRUE(fs::is_directory(package)) << package << " is missing: run scripts/install-deps.sh (npm ci in tools/gltf)";
  const std::string command = "node " + kValidator.string() + " " + gltf.string() + " --report " + report.string() +
                              " > /dev/null 2> " + report.string() + ".stderr";
  const int status = std::system(command.c_str());
  EXPECT_TRUE(fs::is_regular_file(report)) << "the validator did not run (status " << status << ")";
  if (!fs::is_regular_file(report)) return nlohmann::json::object();
  return common::ReadJsonFile(report);
}

std::string Messages(const nlohmann::json& report) {
  std::string text;
  for (const auto& message : report["issues"]["messages"]) text += message.dump() + "\n";
  return text;
}

void ExpectNoErrorsOrWarnings(const fit::Material& material, const testing::TempFolder& folder, const std::string& name) {
  fit::WriteMaterial(folder / name, material);
  const auto result = testing::RunSvbtdf("export " + (folder / name).string() + " --gltf " + (folder / "out").string() +
                                         " --threads 1");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const nlohmann::json report = Validate(folder / "out" / (name + ".gltf"), folder / (name + ".report.json"));
  ASSERT_TRUE(report.contains("issues"));
  EXPECT_EQ(report["issues"]["numErrors"].get<int>(), 0) << Messages(report);
  EXPECT_EQ(report["issues"]["numWarnings"].get<int>(), 0) << Messages(report);
  // The validator read every texture and the buffer (a resource it could not load is an error).
  EXPECT_EQ(report["info"]["resources"].size(), 6u) << report["info"].dump(2);
}

TEST(GltfValidator, ARoughnessRegionsExportHasNoErrorsOrWarnings) {
  const testing::TempFolder folder;
  ExpectNoErrorsOrWarnings(RegionsMaterial(3, 2, 6, {0.02, 0.05, 0.1, 0.2, 0.35, 0.5}), folder, "regions");
}

TEST(GltfValidator, AnAnisotropicExportHasNoErrorsOrWarnings) {
  const testing::TempFolder folder;
  ExpectNoErrorsOrWarnings(RegionsMaterial(2, 1, 5, {0.1, 0.3}, /*anisotropy=*/0.3), folder, "anisotropic");
}

}  // namespace
}  // namespace svbtdf
