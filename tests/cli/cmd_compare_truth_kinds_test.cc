// `svbtdf compare` end to end against a Monte Carlo truth: a uniform fitted material is compared
// with a `--truth montecarlo` simulation of the tiny preset. The Monte Carlo truth has no alpha or
// NDF, so those metrics are null, while the BTDF errors are reported against its rho(x, i, o); and
// `svbtdf report` shows what that truth has.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "run_command.h"
#include "svbtdf/common/atomic_file.h"
#include "svbtdf/fit/material.h"
#include "svbtdf/model/ggx.h"
#include "svbtdf/model/hemicube.h"

namespace svbtdf {
namespace {
namespace fs = std::filesystem;
using testing::RunSvbtdf;

// A 32 x 32 material whose every texel is one GGX 0.2 dual-microfacet texel (one representative).
void WriteUniformMaterial(const fs::path& folder) {
  constexpr int kSize = 32, kResolution = 16;
  fit::Clustering clustering;
  clustering.representatives = {0};
  clustering.cluster.assign(kSize * kSize, 0);
  clustering.weights.assign(kSize * kSize, fit::AffineWeights{{{0, 1.0f}}});
  fit::TexelFitResult fit;
  fit.alpha = 0.5;
  fit.k_s_rgb = {0.9, 0.9, 0.9};
  fit.k_s = 0.9;
  const model::Hemicube grid(kResolution);
  const model::GgxNdf ndf(0.2, 0.2);
  for (int c = 0; c < grid.num_cells(); ++c) fit.ln_d.push_back(std::log(std::max(ndf.D(grid.CellCenter(c)), 1e-6)));
  common::FloatImage rho_d(kSize, kSize, 3, 0.01f);
  fit::WriteMaterial(folder, fit::AssembleMaterial(kSize, kSize, 1.5, kResolution, clustering, {fit}, rho_d));
}

nlohmann::json Compare(const fs::path& material, const fs::path& truth, const fs::path& json) {
  const auto result = RunSvbtdf("-q compare " + material.string() + " " + truth.string() + " --json " + json.string());
  EXPECT_EQ(result.exit_code, 0) << result.output;
  return nlohmann::json::parse(common::ReadTextFile(json));
}

TEST(CompareTruthKinds, ReportsBtdfErrorsAgainstAMonteCarloTruth) {
  const fs::path root = fs::temp_directory_path() / ("svbtdf-compare-mc-" + std::to_string(::getpid()));
  fs::remove_all(root);
  fs::create_directories(root);
  WriteUniformMaterial(root / "material");
  const auto run = RunSvbtdf("-q simulate --preset tiny --threads 2 --truth montecarlo --out " + (root / "mc").string());
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const nlohmann::json mc = Compare(root / "material", root / "mc" / "truth", root / "mc.json");
  std::printf("Monte Carlo truth: held-out rel. RMSE %s, rho_d rel. error %s\n", mc["heldout_rel_rmse"].dump().c_str(),
              mc["rho_d_rel_error_median"].dump().c_str());

  EXPECT_EQ(mc["truth_kind"], "montecarlo");
  for (const char* key : {"alpha_within_0_05", "alpha_error_median", "ndf_rel_l2_median"}) {
    EXPECT_TRUE(mc[key].is_null()) << key << ": " << mc[key];
  }
  // rho_d of the truth's slab materials is 0.005, 0.01 or about 0.015 against the material's 0.01.
  ASSERT_TRUE(mc["rho_d_rel_error_median"].is_number());
  EXPECT_LT(mc["rho_d_rel_error_median"].get<double>(), 1.0);
  // No holdout recorded: every dot is held out, so both RMSEs are the same number.
  EXPECT_EQ(mc["holdout_recorded"], false);
  ASSERT_TRUE(mc["heldout_rel_rmse"].is_number()) << mc.dump();
  EXPECT_DOUBLE_EQ(mc["heldout_rel_rmse"].get<double>(), mc["all_dots_rel_rmse"].get<double>());
  // A uniform GGX 0.2 dual-microfacet texel is a poor stand-in for two rough interfaces (about
  // 1.0 measured): wrong, but finite and not wildly so.
  EXPECT_GT(mc["heldout_rel_rmse"].get<double>(), 0.1);
  EXPECT_LT(mc["heldout_rel_rmse"].get<double>(), 3.0);
  // `svbtdf report --truth` reads the same truth: its rho_d and slab materials beside the material.
  const auto report = RunSvbtdf("-q report " + (root / "material").string() + " --out " + (root / "report").string() +
                                " --truth " + (root / "mc" / "truth").string() + " --compare " + (root / "mc.json").string());
  EXPECT_EQ(report.exit_code, 0) << report.output;
  for (const char* file : {"index.html", "rho_d_truth.png", "slab_material_truth.png"}) {
    EXPECT_TRUE(fs::exists(root / "report" / file)) << file;
  }
  EXPECT_FALSE(fs::exists(root / "report" / "alpha_truth.png"));
  // A truth folder that is neither kind is named.
  common::WriteTextAtomically(root / "mc" / "truth" / "material.json", "{}", /*overwrite=*/true);
  const auto bad = RunSvbtdf("compare " + (root / "material").string() + " " + (root / "mc" / "truth").string());
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("material.json"), std::string::npos) << bad.output;
  fs::remove_all(root);
}

}  // namespace
}  // namespace svbtdf
