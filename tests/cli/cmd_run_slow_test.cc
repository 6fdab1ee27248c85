// The fit's acceptance with every texel fitted (issue 5), label "slow": a few minutes.
#include "fit_chain.h"

namespace svbtdf {
namespace {

// Issue 5's acceptance with every texel fitted, and the cost of clustering (label slow).
TEST_F(FitChain, SlowEveryTexelMeetsTheAcceptanceAndClusteringCostsLittle) {
  const nlohmann::json all = FitAndCompare("all", "--holdout 0.1 --representatives all");
  EXPECT_GE(all["alpha_within_0_05"].get<double>(), 0.9);
  EXPECT_LT(all["ndf_rel_l2_median"].get<double>(), 0.10);
  EXPECT_LT(all["heldout_rel_rmse"].get<double>(), 0.05);
  // Clustering with the interpolated texels refined (refine_texels.h): the issue asks 1% within
  // 1.2x of fitting every texel. Measured on this session: every texel 2.66%; 5% representatives
  // 1.19%, 1% (10 representatives) 1.18%, in seconds instead of minutes. The refined blends of the
  // representatives' tables are less noisy than each texel's own fit.
  const nlohmann::json five = FitAndCompare("five", "--holdout 0.1 --representatives 0.05");
  EXPECT_LT(five["heldout_rel_rmse"].get<double>(), 1.2 * all["heldout_rel_rmse"].get<double>());
  const nlohmann::json one = FitAndCompare("one", "--holdout 0.1 --representatives 0.01");
  EXPECT_LT(one["heldout_rel_rmse"].get<double>(), 1.2 * all["heldout_rel_rmse"].get<double>());
  EXPECT_GE(one["alpha_within_0_05"].get<double>(), 0.9);
}

}  // namespace
}  // namespace svbtdf
