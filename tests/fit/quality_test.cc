// The quality checks of docs/quality.md on hand-made outputs: each fires on a deliberately wrong
// one, with its figures, and none fires on a good one; quality.json round-trips.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>

#include "analytic_store.h"
#include "quality_warnings.h"
#include "small_material.h"
#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/image_io.h"
#include "svbtdf/fit/quality.h"
#include "temp_folder.h"

namespace svbtdf::fit {
namespace {
namespace fs = std::filesystem;
using testing::Checks;
using testing::Find;
using testing::Has;


class StoreCheck : public ::testing::Test {
 protected:
  void SetUp() override {
    common::WriteTextAtomically(dir_ / "processed.json", R"({"format": "svbtdf-processed", "statistics": {"texels": 100, "valid_texels": 100}})");
  }
  void WriteMap(const char* name, int zeros) {
    common::FloatImage map(10, 10, 1, 1.0f);
    for (int t = 0; t < zeros; ++t) map.pixels[t] = 0.0f;
    common::WriteFloatImage(dir_ / name, map);
  }
  svbtdf::testing::TempFolder folder_;
  const fs::path dir_ = folder_.path();
};

TEST_F(StoreCheck, AllTexelsValidAndNoReachMapDrawsNoWarning) {
  WriteMap("mask.exr", 5);
  EXPECT_TRUE(CheckSliceStore(dir_).empty());  // no reach.exr, no statistic: that check is skipped
  WriteMap("reach.exr", 5);
  EXPECT_TRUE(CheckSliceStore(dir_).empty());
}

TEST_F(StoreCheck, FewValidTexelsAndTexelsWithoutDotAreWarnings) {
  WriteMap("mask.exr", 40);
  WriteMap("reach.exr", 20);
  const auto warnings = CheckSliceStore(dir_);
  ASSERT_EQ(Checks(warnings), (std::vector<std::string>{"valid-texels", "texels-without-dot"}));
  EXPECT_NE(warnings[0].figures.find("60 of 100 texels valid"), std::string::npos) << warnings[0].figures;
  EXPECT_NE(warnings[0].likely_cause.find("exposure is too low"), std::string::npos);
  EXPECT_EQ(warnings[1].file, (dir_ / "reach.exr").string());
  EXPECT_NE(warnings[1].figures.find("20 of 100 texels"), std::string::npos) << warnings[1].figures;
  EXPECT_NE(warnings[1].likely_cause.find("widen the dot grid"), std::string::npos);
}

TEST_F(StoreCheck, TheManifestsCountServesWhenThereIsNoReachMap) {
  WriteMap("mask.exr", 0);
  common::WriteTextAtomically(dir_ / "processed.json",
                      R"({"statistics": {"texels": 100, "valid_texels": 100, "texels_without_dot_beneath": 12}})");
  const auto warnings = CheckSliceStore(dir_);
  ASSERT_EQ(Checks(warnings), std::vector<std::string>{"texels-without-dot"});
  EXPECT_EQ(warnings[0].file, (dir_ / "processed.json").string());
  common::WriteTextAtomically(dir_ / "processed.json",
                      R"({"statistics": {"texels": 100, "valid_texels": 100, "texels_without_dot_beneath": 3}})");
  EXPECT_TRUE(CheckSliceStore(dir_).empty());
}

// The flat white frame's noise (processed.json `white_exitance_noise`): 1% or more in any channel
// is a warning naming the manifest with the three figures; the presets' 0.2% is not; a store
// written before it was measured has none to check; one that is not three numbers is refused.
TEST_F(StoreCheck, ANoisyFlatWhiteIsAWarning) {
  WriteMap("mask.exr", 0);
  const auto with_noise = [&](const char* noise) {
    common::WriteTextAtomically(dir_ / "processed.json",
                                std::string(R"({"statistics": {"texels": 100}, "white_exitance_noise": )") + noise + "}");
    return CheckSliceStore(dir_);
  };
  EXPECT_TRUE(with_noise("[0.0017, 0.0018, 0.0018]").empty());
  const auto warnings = with_noise("[0.004, 0.012, 0.005]");
  ASSERT_EQ(Checks(warnings), std::vector<std::string>{"flat-white-noise"});
  EXPECT_EQ(warnings[0].file, (dir_ / "processed.json").string());
  EXPECT_NE(warnings[0].figures.find("0.40% / 1.20% / 0.50%"), std::string::npos) << warnings[0].figures;
  EXPECT_NE(warnings[0].likely_cause.find("longer exposure"), std::string::npos);
  EXPECT_THROW(with_noise("\"high\""), common::Error);
}

// A slice seen from above, its dots on a square grid 2 degrees apart (21 x 21): rho = 0.8 where
// `lit(column, row)`, 1 at the lobe's peak (the centre dot, when lit) and 0.01 elsewhere.
template <typename Lit>
TexelSlice GridSlice(Lit lit) {
  TexelSlice slice;
  const double step = std::tan(2.0 * model::kPi / 180.0);
  for (int row = -10; row <= 10; ++row) {
    for (int column = -10; column <= 10; ++column) {
      slice.light.push_back(model::Vec3(column * step, row * step, -1.0).normalized());
      slice.rho.push_back(lit(column, row) ? (row == 0 && column == 0 ? 1.0 : 0.8) : 0.01);
    }
  }
  return slice;
}

TEST(DotsAcrossLobe, CountsTheRowsOfDotsAboveHalfMaximumAcrossTheLobesNarrowestDirection) {
  // One column of lit dots, straight or diagonal: one dot across, however long.
  EXPECT_NEAR(DotsAcrossLobe(GridSlice([](int c, int r) { return c == 0 && std::abs(r) <= 6; })), 1.0, 1e-6);
  EXPECT_NEAR(DotsAcrossLobe(GridSlice([](int c, int r) { return c == r && std::abs(r) <= 6; })), 1.0, 1e-6);
  EXPECT_NEAR(DotsAcrossLobe(GridSlice([](int, int r) { return r == 0; })), 1.0, 1e-6);
  // Two and three columns (the grid's projection onto the tangent plane bends it by < 1%).
  EXPECT_NEAR(DotsAcrossLobe(GridSlice([](int c, int r) { return (c == 0 || c == 1) && std::abs(r) <= 6; })), 2.0, 0.02);
  EXPECT_NEAR(DotsAcrossLobe(GridSlice([](int c, int r) { return std::abs(c) <= 1 && std::abs(r) <= 6; })), 3.0, 0.03);
  // A round lobe 7 dots across: its disk's variance, r^2 / 4 for r = 3.5 dots, gives about 6.
  const double disk = DotsAcrossLobe(GridSlice([](int c, int r) { return c * c + r * r <= 12; }));
  EXPECT_GT(disk, 5.5);
  EXPECT_LT(disk, 7.0);
  // A single bright dot; no positive sample at all.
  EXPECT_EQ(DotsAcrossLobe(GridSlice([](int c, int r) { return c == 4 && r == -2; })), 1.0);
  TexelSlice dark = GridSlice([](int, int) { return false; });
  for (double& rho : dark.rho) rho = 0.0;
  EXPECT_EQ(DotsAcrossLobe(dark), 0.0);
}

// Stores synthesised from a GGX material 0.16-0.28 rough (tests/support/analytic_store.h): its
// lobes span one dot or less on most texels of a 12 x 12 grid (83%) and 2.5 or more on every
// texel of a 24 x 24 one.
TEST(StoreLobeCheck, LobesNarrowerThanTwoDotsAcrossAreAWarningAndDenserDotsClearIt) {
  const svbtdf::testing::TempFolder folder;
  const svbtdf::testing::AnalyticMaterial material{8, 8};
  svbtdf::testing::WriteAnalyticStore(folder.path() / "sparse", material, 12, 0.01);
  const auto sparse = CheckSliceStore(folder.path() / "sparse");
  ASSERT_EQ(Checks(sparse), std::vector<std::string>{"lobe-undersampled"});
  EXPECT_EQ(sparse[0].stage, "process");
  EXPECT_EQ(sparse[0].file, (folder.path() / "sparse" / "samples.f16").string());
  EXPECT_NE(sparse[0].figures.find("of 64 texels checked"), std::string::npos) << sparse[0].figures;
  EXPECT_NE(sparse[0].likely_cause.find("denser dots"), std::string::npos);
  svbtdf::testing::WriteAnalyticStore(folder.path() / "dense", material, 24, 0.01);
  EXPECT_TRUE(CheckSliceStore(folder.path() / "dense").empty());
}

Material GoodMaterial() {
  Material m = SmallMaterial();
  for (float& r : m.residual.pixels) r = 0.04f;
  return m;
}

TEST(QualityCheck, AGoodMaterialDrawsNoWarning) {
  EXPECT_TRUE(CheckMaterial(GoodMaterial(), "M").empty());
  EXPECT_TRUE(CheckMaterial(SmallMaterial(), "M").empty());  // residuals unknown (-1): not counted
}

TEST(QualityCheck, LargeResidualsHugeKsAndAlphaAtItsBoundsAreWarnings) {
  Material m = GoodMaterial();
  m.residual.pixels = {0.37f, 0.8f, 0.04f, 0.5f, 0.03f, -1.0f};
  m.k_s.at(2, 1, 1) = 1.5e5f;
  m.alpha = common::FloatImage(3, 2, 1, 1.0f);
  const auto warnings = CheckMaterial(m, "MAT");
  ASSERT_EQ(Checks(warnings), (std::vector<std::string>{"fit-residual", "k_s-implausible", "alpha-at-bounds"}));
  EXPECT_EQ(warnings[0].file, "MAT/residual.exr");
  EXPECT_NE(warnings[0].figures.find("3 of 5 texels (60.0%"), std::string::npos) << warnings[0].figures;
  EXPECT_NE(warnings[0].figures.find("max 0.800"), std::string::npos) << warnings[0].figures;
  EXPECT_NE(warnings[1].figures.find("1 of 6 texels"), std::string::npos) << warnings[1].figures;
  EXPECT_NE(warnings[1].figures.find("1.5e+05 at texel (2, 1)"), std::string::npos) << warnings[1].figures;
  EXPECT_NE(warnings[2].figures.find("100.0% at alpha = 1"), std::string::npos) << warnings[2].figures;
  // A non-finite k_s (the reader refuses it, but a fit could make one) counts too.
  Material nan = GoodMaterial();
  nan.k_s.at(0, 0, 0) = std::nanf("");
  EXPECT_EQ(Checks(CheckMaterial(nan, "M")), std::vector<std::string>{"k_s-implausible"});
  // The baseline has no alpha: its zero map is not a warning.
  Material baseline = GoodMaterial();
  baseline.model = MaterialModel::kWalterGgx;
  baseline.alpha = common::FloatImage(3, 2, 1, 0.0f);
  EXPECT_TRUE(CheckMaterial(baseline, "M").empty());
}

TEST(QualityFile, RoundTripsAndRefusesOtherVersions) {
  const svbtdf::testing::TempFolder folder;
  const fs::path& dir = folder.path();
  std::vector<QualityWarning> read;
  EXPECT_FALSE(ReadQuality(dir, &read));
  const std::vector<QualityWarning> warnings = {{"calibrate", "a/calibration.json", "dot-residual", "what", "1 mm", "cause"},
                                                {"fit", "m/k_s.exr", "k_s-implausible", "w2", "", ""}};
  WriteQuality(dir, warnings);
  ASSERT_TRUE(ReadQuality(dir, &read));
  ASSERT_EQ(read.size(), 2u);
  EXPECT_EQ(read[0].Line(), warnings[0].Line());
  EXPECT_EQ(read[1].Line(), "warning: fit: m/k_s.exr: w2");
  nlohmann::json json = QualityToJson(warnings);
  EXPECT_EQ(json["format"], "svbtdf-quality");
  EXPECT_EQ(json["thresholds"]["k_s_max"], kMaxPlausibleKs);
  EXPECT_EQ(json["thresholds"]["min_dots_across_lobe"], kMinDotsAcrossLobe);
  json["version"] = 99;
  EXPECT_THROW(QualityFromJson(json, "q.json"), common::Error);
}

}  // namespace
}  // namespace svbtdf::fit
