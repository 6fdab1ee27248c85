// `svbtdf fit` on a small processed store synthesised from a known material
// (tests/support/analytic_store.h): arguments, refusals, and the ggx baseline through `svbtdf eval`.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>

#include "analytic_store.h"
#include "run_command.h"
#include "svbtdf/common/atomic_file.h"
#include "svbtdf/fit/material.h"
#include "temp_folder.h"

namespace svbtdf {
namespace {
namespace fs = std::filesystem;
using testing::RunSvbtdf;

class FitCommand : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    folder_ = std::make_unique<svbtdf::testing::TempFolder>("fit-command");
    root_ = folder_->path();
    testing::WriteAnalyticStore(root_ / "processed", testing::AnalyticMaterial{6, 6}, 16, 0.01);
  }
  static void TearDownTestSuite() { folder_.reset(); }
  static std::string Fit(const std::string& out, const std::string& options) {
    return "fit " + (root_ / "processed").string() + " --out " + (root_ / out).string() + " " + options;
  }
  static inline fs::path root_;
  static inline std::unique_ptr<svbtdf::testing::TempFolder> folder_;
};

TEST_F(FitCommand, BadArgumentsExitWithTwoNamingTheArgument) {
  const struct {
    std::string options, named;
  } cases[] = {{"--holdout 0.95", "--holdout"},
               {"--holdout -1", "--holdout"},
               {"--model walter", "--model"},
               {"--representatives 2", "--representatives"},
               {"--representatives some", "--representatives"},
               {"--eta 0.9", "--eta"},
               {"--model-error-pool -1", "--model-error-pool"},
               {"--model-error-pool wide", "--model-error-pool"},
               {"--internal-reflection", "--fixed-horizon"},
               {"--internal-reflection --fixed-horizon --model ggx", "--internal-reflection"},
               {"--internal-reflection --fixed-horizon --model slab", "--internal-reflection"},
               {"--anisotropic-sides", "--anisotropic-sides"}};
  for (const auto& c : cases) {
    const auto result = RunSvbtdf(Fit("bad", c.options));
    EXPECT_EQ(result.exit_code, 2) << c.options << ": " << result.output;
    EXPECT_NE(result.output.find(c.named), std::string::npos) << c.options << ": " << result.output;
  }
  EXPECT_FALSE(fs::exists(root_ / "bad" / "material.json"));
  const auto missing = RunSvbtdf("fit " + (root_ / "nowhere").string() + " --out " + (root_ / "m").string());
  EXPECT_EQ(missing.exit_code, 2) << missing.output;
  EXPECT_NE(missing.output.find("nowhere"), std::string::npos) << missing.output;
}

TEST_F(FitCommand, GgxBaselineIsFittedWrittenAndEvaluated) {
  const auto fitted = RunSvbtdf(Fit("ggx", "--model ggx --representatives 0.25 --holdout 0.1"));
  ASSERT_EQ(fitted.exit_code, 0) << fitted.output;
  EXPECT_NE(fitted.output.find("walter-ggx"), std::string::npos) << fitted.output;
  EXPECT_NE(fitted.output.find("material: " + (root_ / "ggx").string()), std::string::npos) << fitted.output;
  const nlohmann::json manifest = nlohmann::json::parse(common::ReadTextFile(root_ / "ggx" / "material.json"));
  EXPECT_EQ(manifest["btdf"], "walter-ggx");
  EXPECT_EQ(manifest["version"], 2);
  EXPECT_EQ(manifest["provenance"]["holdout"]["dots"].size(), 26u);  // 10% of 256 dots
  const auto eval = RunSvbtdf("eval " + (root_ / "ggx").string() + " --texel 2 3 --wi 0 0.3 -1 --wo 0 -0.7 0.7 --json");
  ASSERT_EQ(eval.exit_code, 0) << eval.output;
  const nlohmann::json value = nlohmann::json::parse(eval.output);
  EXPECT_EQ(value["btdf"], "walter-ggx");
  EXPECT_GT(value["baseline_alpha_x"].get<double>(), 0.0);
  // The command evaluates through the library's one path: the same value as in process.
  const fit::Material material = fit::ReadMaterial(root_ / "ggx");
  const model::Rgb expected = fit::MaterialEvaluator(material).Evaluate(2, 3, model::Vec3(0, 0.3, -1).normalized(),
                                                                 model::Vec3(0, -0.7, 0.7).normalized());
  EXPECT_NEAR(value["rgb"][0].get<double>(), expected[0], 1e-6 * std::abs(expected[0]) + 1e-12);
  EXPECT_GE(value["rgb"][0].get<double>(), material.rho_d.at(2, 3, 0));
}

// --model slab: a material of format version 6 whose texels `svbtdf eval` shows as two
// interfaces, R = k_s rho + rho_d through the library's one path; `svbtdf export` refuses it in
// one line naming its manifest, and writes nothing.
TEST_F(FitCommand, TheSlabModelIsWrittenEvaluatedAndNotExported) {
  // Isotropic sides (the default): the anisotropic search is the library's to test (tests/fit).
  const auto fitted = RunSvbtdf(Fit("slab", "--model slab --representatives 0.25 --holdout 0.1"));
  ASSERT_EQ(fitted.exit_code, 0) << fitted.output;
  const nlohmann::json manifest = nlohmann::json::parse(common::ReadTextFile(root_ / "slab" / "material.json"));
  EXPECT_EQ(manifest["btdf"], "slab");
  EXPECT_EQ(manifest["version"], 6);
  EXPECT_FALSE(manifest["provenance"]["settings"]["slab_anisotropic"].get<bool>());
  const auto eval = RunSvbtdf("eval " + (root_ / "slab").string() + " --texel 2 3 --wi 0 0.3 -1 --wo 0 -0.7 0.7 --json");
  ASSERT_EQ(eval.exit_code, 0) << eval.output;
  const nlohmann::json value = nlohmann::json::parse(eval.output);
  EXPECT_EQ(value["btdf"], "slab");
  for (const char* side : {"slab_entry", "slab_exit"}) {
    const nlohmann::json& s = value[side];
    EXPECT_NEAR(s["roughness"].get<double>(), std::sqrt(s["alpha_x"].get<double>() * s["alpha_y"].get<double>()), 1e-9) << side;
    EXPECT_EQ(s["alpha_x"].get<double>(), s["alpha_y"].get<double>()) << side;  // isotropic
  }
  for (int c = 0; c < 3; ++c) {
    const double expected = value["k_s"][c].get<double>() * value["rho"].get<double>() + value["rho_d"][c].get<double>();
    EXPECT_NEAR(value["rgb"][c].get<double>(), expected, 1e-6 * expected);
  }
  const auto text = RunSvbtdf("eval " + (root_ / "slab").string() + " --texel 2 3 --wi 0 0.3 -1 --wo 0 -0.7 0.7");
  EXPECT_NE(text.output.find("slab: entry "), std::string::npos) << text.output;
  const auto exported = RunSvbtdf("export " + (root_ / "slab").string() + " --gltf " + (root_ / "slab-gltf").string());
  EXPECT_EQ(exported.exit_code, 2) << exported.output;
  EXPECT_NE(exported.output.find((root_ / "slab" / "material.json").string()), std::string::npos) << exported.output;
  EXPECT_NE(exported.output.find("slab material"), std::string::npos) << exported.output;
  EXPECT_FALSE(fs::exists(root_ / "slab-gltf"));
}

// --internal-reflection: a material of format version 4 whose `svbtdf eval` shows the term and
// adds it to R (R = k_s (blend + term) + rho_d), through the library's one path.
TEST_F(FitCommand, TheInternalReflectionTermIsWrittenAndEvaluated) {
  const auto fitted = RunSvbtdf(Fit("internal", "--internal-reflection --fixed-horizon --representatives 0.25"));
  ASSERT_EQ(fitted.exit_code, 0) << fitted.output;
  const nlohmann::json manifest = nlohmann::json::parse(common::ReadTextFile(root_ / "internal" / "material.json"));
  EXPECT_EQ(manifest["version"], 4);
  EXPECT_TRUE(manifest["internal_reflection"].get<bool>());
  const auto eval = RunSvbtdf("eval " + (root_ / "internal").string() + " --texel 2 3 --wi 0.4 0.3 -1 --wo 0 -0.7 0.7 --json");
  ASSERT_EQ(eval.exit_code, 0) << eval.output;
  const nlohmann::json value = nlohmann::json::parse(eval.output);
  const double internal = value["internal_reflection"].get<double>();
  EXPECT_GT(internal, 0.0);
  for (int c = 0; c < 3; ++c) {
    const double expected = value["k_s"][c].get<double>() * value["rho"].get<double>() + value["rho_d"][c].get<double>();
    EXPECT_NEAR(value["rgb"][c].get<double>(), expected, 1e-6 * expected);
  }
  const double blend = std::exp(value["alpha"].get<double>() * std::log(value["rho_T"].get<double>()) +
                                (1 - value["alpha"].get<double>()) * std::log(value["rho_B"].get<double>()));
  EXPECT_NEAR(value["rho"].get<double>(), blend + internal, 1e-9 * (blend + internal));
}

TEST_F(FitCommand, AnExistingMaterialIsNeverOverwritten) {
  const auto first = RunSvbtdf(Fit("dual", "--representatives 0.1"));
  ASSERT_EQ(first.exit_code, 0) << first.output;
  EXPECT_NE(first.output.find("dual-microfacet"), std::string::npos) << first.output;
  const std::string before = common::ReadTextFile(root_ / "dual" / "material.json");
  const auto second = RunSvbtdf(Fit("dual", "--representatives 0.1"));
  EXPECT_EQ(second.exit_code, 2) << second.output;
  EXPECT_NE(second.output.find("never overwritten"), std::string::npos) << second.output;
  EXPECT_EQ(common::ReadTextFile(root_ / "dual" / "material.json"), before);
  const nlohmann::json manifest = nlohmann::json::parse(before);
  // Issue 20: the standard errors are maps of material format version 3; without them
  // (--no-uncertainty) dual-microfacet materials stay readable by version 1 readers.
  EXPECT_EQ(manifest["version"], 3);
  EXPECT_EQ(manifest["maps"]["alpha_se"], "alpha_se.exr");
  EXPECT_EQ(manifest["btdf"], "dual-microfacet");
  const auto plain = RunSvbtdf(Fit("plain", "--representatives 0.1 --no-uncertainty"));
  ASSERT_EQ(plain.exit_code, 0) << plain.output;
  const nlohmann::json plain_manifest = nlohmann::json::parse(common::ReadTextFile(root_ / "plain" / "material.json"));
  EXPECT_EQ(plain_manifest["version"], 1);
  EXPECT_FALSE(plain_manifest["maps"].contains("alpha_se"));
  EXPECT_FALSE(fit::ReadMaterial(root_ / "plain").has_uncertainty());
}

}  // namespace
}  // namespace svbtdf
