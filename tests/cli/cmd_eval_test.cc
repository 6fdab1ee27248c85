// `svbtdf eval MATERIAL --texel U V --wi .. --wo .. --json` against the library's evaluation of
// the same texel (issue 5's command-line contract).
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "run_command.h"
#include "small_material.h"
#include "svbtdf/fit/material.h"
#include "svbtdf/model/ggx.h"
#include "temp_folder.h"

namespace svbtdf {
namespace {
namespace fs = std::filesystem;
using testing::RunSvbtdf;

TEST(EvalCommand, PrintsTheMaterialsValueAtATexel) {
  const testing::TempFolder folder;
  const fs::path dir = folder / "material";  // not there yet: WriteMaterial creates it
  const fit::Material material = SmallMaterial();
  fit::WriteMaterial(dir, material);
  const auto result = RunSvbtdf("eval " + dir.string() + " --texel 2 1 --wi 0.2 0.1 -1 --wo -0.3 0 1 --json");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const nlohmann::json json = nlohmann::json::parse(result.output);
  const model::Rgb expected = fit::MaterialEvaluator(material).Evaluate(2, 1, model::Vec3(0.2, 0.1, -1).normalized(),
                                                                 model::Vec3(-0.3, 0, 1).normalized());
  ASSERT_GT(expected[0], 0.02);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(json["rgb"][c].get<double>(), expected[c], 1e-6 * expected[c]);
  // Outside the material, or a missing material: one clear line, exit 2 or 1.
  const auto outside = RunSvbtdf("eval " + dir.string() + " --texel 3 0 --wi 0 0 -1 --wo 0 0 1");
  EXPECT_EQ(outside.exit_code, 2) << outside.output;
  EXPECT_NE(outside.output.find("--texel"), std::string::npos);
  const auto missing = RunSvbtdf("eval " + (dir / "nope").string() + " --texel 0 0 --wi 0 0 -1 --wo 0 0 1");
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_NE(missing.output.find("material.json"), std::string::npos);
}

}  // namespace
}  // namespace svbtdf
