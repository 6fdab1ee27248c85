// The command-line contract of `svbtdf btdf eval` (issue 2): JSON keys and values equal to the
// library's, and bad input rejected with one clear line and exit code 2.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "run_command.h"
#include "svbtdf/model/dual_microfacet.h"
#include "svbtdf/model/ggx.h"

namespace svbtdf {
namespace {

using testing::RunSvbtdf;

TEST(BtdfEvalCommand, PrintsTheModelValuesAsJson) {
  const auto result = RunSvbtdf(
      "btdf eval --ndf ggx --roughness 0.3 --eta 1.5 --alpha 0.4 --shadowing smith --shadowing-roughness 0.25 "
      "--wi 0.3 0.1 -1 --wo -0.2 0.1 1 --json");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const nlohmann::json json = nlohmann::json::parse(result.output);
  const model::Vec3 wi = model::Vec3(0.3, 0.1, -1).normalized(), wo = model::Vec3(-0.2, 0.1, 1).normalized();
  const model::GgxNdf ndf(0.3);
  const model::DualMicrofacetModel model(1.5, model::SmithShadowing::Ggx(0.25));
  const double rho_T = model.RhoT(ndf, wi, wo), rho_B = model.RhoB(ndf, wi, wo);
  ASSERT_GT(rho_T, 0.0);
  EXPECT_NEAR(json["rho_T"].get<double>(), rho_T, 1e-12 * rho_T);
  EXPECT_NEAR(json["rho_B"].get<double>(), rho_B, 1e-12 * rho_B);
  EXPECT_NEAR(json["rho"].get<double>(), model::LogBlend(rho_T, rho_B, 0.4), 1e-12 * rho_T);
}

TEST(BtdfEvalCommand, BadInputIsOneClearLineAndExitCodeTwo) {
  const std::string directions = " --wi 0 0 -1 --wo 0 0 1";
  for (const std::string& arguments :
       {std::string("btdf eval --wi 0 0 0 --wo 0 0 1"), std::string("btdf eval --wi 0 0 1 --wo 0 0 1"),
        "btdf eval --eta 1.0" + directions, "btdf eval --eta 0.5" + directions,
        "btdf eval --roughness -0.1" + directions, "btdf eval --alpha 1.5" + directions,
        "btdf eval --shadowing smith" + directions, "btdf eval --ndf nope" + directions,
        std::string("btdf eval --wi 0 0 -1")}) {
    const auto result = RunSvbtdf(arguments);
    EXPECT_EQ(result.exit_code, 2) << arguments << "\n" << result.output;
    EXPECT_EQ(result.output.rfind("svbtdf: error: ", 0), 0u) << arguments << "\n" << result.output;
    EXPECT_EQ(std::count(result.output.begin(), result.output.end(), '\n'), 1) << result.output;
  }
}

}  // namespace
}  // namespace svbtdf
