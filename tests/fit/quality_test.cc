// The quality checks of docs/quality.md on hand-made outputs: each fires on a deliberately wrong
// one, with its figures, and none fires on a good one; quality.json round-trips.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>

#include "small_material.h"
#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/image_io.h"
#include "svbtdf/fit/quality.h"
#include "temp_folder.h"

namespace svbtdf::fit {
namespace {
namespace fs = std::filesystem;

// A calibration as a good `svbtdf calibrate` writes it: 36 dots found within blob noise, all
// board views used at 0.1 px.
calib::SessionCalibration GoodCalibration() {
  calib::SessionCalibration c;
  c.camera.rms_px = 0.08;
  for (int v = 0; v < 8; ++v) {
    calib::ViewReport view;
    view.source = "board/v0" + std::to_string(v);
    view.used = true;
    view.rms_px = 0.08;
    c.camera.views.push_back(view);
  }
  c.sample_plane.rms_px = 0.12;
  for (int q = 0; q < 36; ++q) {
    calib::DotPosition dot;
    dot.residual_mm = 0.01 + 0.001 * q;
    c.monitor.dots.push_back(dot);
  }
  c.monitor.residual_rms_mm = 0.02;
  c.monitor.residual_max_mm = 0.045;
  return c;
}

std::vector<std::string> Checks(const std::vector<QualityWarning>& warnings) {
  std::vector<std::string> checks;
  for (const QualityWarning& w : warnings) checks.push_back(w.check);
  return checks;
}

bool Has(const std::vector<QualityWarning>& warnings, const std::string& check) {
  const auto checks = Checks(warnings);
  return std::find(checks.begin(), checks.end(), check) != checks.end();
}

const QualityWarning& Find(const std::vector<QualityWarning>& warnings, const std::string& check) {
  for (const QualityWarning& w : warnings) {
    if (w.check == check) return w;
  }
  throw std::runtime_error("no " + check);
}

TEST(QualityCheck, AGoodCalibrationDrawsNoWarning) {
  EXPECT_TRUE(CheckCalibration(GoodCalibration(), "calibration.json").empty());
  // The truth calibration of the tests (no views, no residuals) neither.
  EXPECT_TRUE(CheckCalibration(calib::SessionCalibration{}, "calibration.json").empty());
}

TEST(QualityCheck, DotsFarFromTheGridAreAWarningWithFiguresAndCause) {
  calib::SessionCalibration c = GoodCalibration();
  c.monitor.dots[7].residual_mm = 2.4;
  c.monitor.dots[8].residual_mm = 1.1;
  c.monitor.residual_max_mm = 2.4;
  c.monitor.residual_rms_mm = 0.45;
  const auto warnings = CheckCalibration(c, "SESSION/calibration.json");
  ASSERT_EQ(Checks(warnings), std::vector<std::string>{"dot-residual"});
  const QualityWarning& w = warnings.front();
  EXPECT_EQ(w.stage, "calibrate");
  const std::string line = w.Line();
  EXPECT_EQ(line.rfind("warning: calibrate: SESSION/calibration.json: ", 0), 0u) << line;
  EXPECT_NE(line.find("RMS 0.450 mm, max 2.400 mm at dot 7"), std::string::npos) << line;
  EXPECT_NE(line.find("2 of 36 found dots"), std::string::npos) << line;
  EXPECT_NE(line.find("mislabelled (monitor orientation"), std::string::npos) << line;
  // The RMS alone also fires (many dots a little off).
  calib::SessionCalibration rms = GoodCalibration();
  rms.monitor.residual_rms_mm = 0.15;
  EXPECT_TRUE(Has(CheckCalibration(rms, "c"), "dot-residual"));
}

TEST(QualityCheck, MissingDotsHighReprojectionAndDroppedViewsAreWarnings) {
  calib::SessionCalibration c = GoodCalibration();
  for (int q = 0; q < 4; ++q) c.monitor.dots[q].residual_mm = -1;  // 4 of 36 > 5%
  c.camera.rms_px = 1.7;
  for (int v = 0; v < 3; ++v) {
    c.camera.views[v].used = false;
    c.camera.views[v].dropped_because = "board not found";
  }
  c.sample_plane.rms_px = 2.5;
  const auto warnings = CheckCalibration(c, "calibration.json");
  EXPECT_EQ(Checks(warnings), (std::vector<std::string>{"dots-missing", "camera-rms", "views-dropped", "sample-plane-rms"}));
  EXPECT_NE(Find(warnings, "dots-missing").figures.find("4 of 36 dots not found"), std::string::npos);
  EXPECT_NE(Find(warnings, "camera-rms").figures.find("1.700 px"), std::string::npos);
  EXPECT_NE(Find(warnings, "views-dropped").figures.find("board/v00: board not found"), std::string::npos);
  // One missing dot of 36 and one dropped view of 8 are within the limits.
  calib::SessionCalibration few = GoodCalibration();
  few.monitor.dots[3].residual_mm = -1;
  few.camera.views[2].used = false;
  EXPECT_TRUE(CheckCalibration(few, "c").empty());
}

class StoreCheck : public ::testing::Test {
 protected:
  void SetUp() override {
    WriteTextAtomically(dir_ / "processed.json", R"({"format": "svbtdf-processed", "statistics": {"texels": 100, "valid_texels": 100}})");
  }
  void WriteMap(const char* name, int zeros) {
    FloatImage map(10, 10, 1, 1.0f);
    for (int t = 0; t < zeros; ++t) map.pixels[t] = 0.0f;
    WriteFloatImage(dir_ / name, map);
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
  WriteTextAtomically(dir_ / "processed.json",
                      R"({"statistics": {"texels": 100, "valid_texels": 100, "texels_without_dot_beneath": 12}})");
  const auto warnings = CheckSliceStore(dir_);
  ASSERT_EQ(Checks(warnings), std::vector<std::string>{"texels-without-dot"});
  EXPECT_EQ(warnings[0].file, (dir_ / "processed.json").string());
  WriteTextAtomically(dir_ / "processed.json",
                      R"({"statistics": {"texels": 100, "valid_texels": 100, "texels_without_dot_beneath": 3}})");
  EXPECT_TRUE(CheckSliceStore(dir_).empty());
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
  m.alpha = FloatImage(3, 2, 1, 1.0f);
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
  baseline.alpha = FloatImage(3, 2, 1, 0.0f);
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
  json["version"] = 99;
  EXPECT_THROW(QualityFromJson(json, "q.json"), Error);
}

}  // namespace
}  // namespace svbtdf::fit
