// `svbtdf compare MATERIAL TRUTH --json FILE` (issue 5's metrics): a material built exactly from
// the simulator's truth scores (near) perfectly, and each kind of error shows in its own metric.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "material_from_truth.h"
#include "run_command.h"
#include "shared_test_data.h"
#include "svbtdf/common/atomic_file.h"
#include "svbtdf/fit/material.h"
#include "svbtdf/simulate/truth_io.h"

namespace svbtdf {
namespace {
namespace fs = std::filesystem;
using testing::RunSvbtdf;

class CompareCommand : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    root_ = fs::temp_directory_path() / ("svbtdf-compare-" + std::to_string(::getpid()));
    fs::remove_all(root_);
    // Simulated once for all of the program's tests (ctest runs each in a process of its own).
    sim_ = testing::SharedTestData("compare", "simulate --preset tiny", [](const fs::path& shared) {
      const auto result = RunSvbtdf("simulate --preset tiny --out " + (shared / "sim").string());
      ASSERT_EQ(result.exit_code, 0) << result.output;
    }) / "sim";
  }
  static void TearDownTestSuite() { fs::remove_all(root_); }

  static nlohmann::json Compare(const fit::Material& material, const std::string& name) {
    fit::WriteMaterial(root_ / name, material);
    const fs::path json = root_ / (name + ".json");
    const auto result = RunSvbtdf("compare " + (root_ / name).string() + " " + (sim_ / "truth").string() +
                                  " --json " + json.string());
    EXPECT_EQ(result.exit_code, 0) << result.output;
    return nlohmann::json::parse(common::ReadTextFile(json));
  }

  static fs::path root_;  // this process's outputs
  static fs::path sim_;   // the shared simulation: read, never written
};
fs::path CompareCommand::root_;
fs::path CompareCommand::sim_;

TEST_F(CompareCommand, TheTruthItselfScoresNearPerfectly) {
  const simulate::MaterialTruth truth = simulate::ReadMaterialTruth(sim_ / "truth");
  const nlohmann::json metrics = Compare(MaterialFromTruth(truth), "exact");
  std::printf("%s\n", metrics.dump().c_str());
  EXPECT_EQ(metrics["alpha_within_0_05"].get<double>(), 1.0);
  EXPECT_LT(metrics["alpha_error_median"].get<double>(), 1e-6);
  // Only the tabulation of the analytic NDF on a 32x32 hemicube separates the two.
  EXPECT_LT(metrics["ndf_rel_l2_median"].get<double>(), 0.05);
  EXPECT_LT(metrics["rho_d_rel_error_median"].get<double>(), 1e-6);
  EXPECT_LT(metrics["heldout_rel_rmse"].get<double>(), 0.05);
}

TEST_F(CompareCommand, EachErrorShowsInItsOwnMetric) {
  const simulate::MaterialTruth truth = simulate::ReadMaterialTruth(sim_ / "truth");
  fit::Material shifted = MaterialFromTruth(truth);
  for (float& a : shifted.alpha.pixels) a = a > 0.5f ? a - 0.1f : a + 0.1f;
  for (float& d : shifted.rho_d.pixels) d *= 1.2f;
  const nlohmann::json metrics = Compare(shifted, "shifted");
  EXPECT_EQ(metrics["alpha_within_0_05"].get<double>(), 0.0);
  EXPECT_NEAR(metrics["alpha_error_median"].get<double>(), 0.1, 1e-4);
  EXPECT_NEAR(metrics["rho_d_rel_error_median"].get<double>(), 0.2, 1e-3);
  EXPECT_LT(metrics["ndf_rel_l2_median"].get<double>(), 0.05);  // the NDFs are untouched
  const nlohmann::json exact = Compare(MaterialFromTruth(truth), "exact2");
  EXPECT_GT(metrics["heldout_rel_rmse"].get<double>(), exact["heldout_rel_rmse"].get<double>() + 0.01);
}

TEST_F(CompareCommand, RefusesToOverwriteItsOutputAndMismatchedSizes) {
  const simulate::MaterialTruth truth = simulate::ReadMaterialTruth(sim_ / "truth");
  fit::WriteMaterial(root_ / "m", MaterialFromTruth(truth));
  const fs::path json = root_ / "exists.json";
  common::WriteTextAtomically(json, "{}");
  auto result = RunSvbtdf("compare " + (root_ / "m").string() + " " + (sim_ / "truth").string() + " --json " +
                          json.string());
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.output.find("already exists"), std::string::npos) << result.output;
  result = RunSvbtdf("compare " + (sim_ / "truth").string() + " " + (sim_ / "truth").string());
  EXPECT_NE(result.exit_code, 0) << result.output;  // a truth folder is not a material
}

}  // namespace
}  // namespace svbtdf
