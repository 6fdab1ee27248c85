// report/page_data.h: base64, numbers in words with their targets, the calibration summary's
// doubts, and the glTF with its files embedded.
#include "svbtdf/report/page_data.h"

#include <gtest/gtest.h>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "temp_folder.h"

namespace svbtdf::report {
namespace {

TEST(PageData, Base64MatchesTheStandardsVectors) {
  // RFC 4648, section 10.
  EXPECT_EQ(Base64(""), "");
  EXPECT_EQ(Base64("f"), "Zg==");
  EXPECT_EQ(Base64("fo"), "Zm8=");
  EXPECT_EQ(Base64("foo"), "Zm9v");
  EXPECT_EQ(Base64("foobar"), "Zm9vYmFy");
  EXPECT_EQ(Base64(std::string("\xff\x00\x10", 3)), "/wAQ");
}

TEST(PageData, FormatsNumbersForPeople) {
  EXPECT_EQ(FormatPercent(0.008290762688380592), "0.829%");
  EXPECT_EQ(FormatPercent(0.9615), "96.2%");
  EXPECT_EQ(FormatNumber(1.41592, "px"), "1.42 px");
  EXPECT_EQ(FormatNumber(NAN), "n/a");
  EXPECT_EQ(FormatNumber(1000), "1000");  // counts in full, not 1e+03
  EXPECT_EQ(FormatNumber(1234.6, "px"), "1235 px");
  EXPECT_EQ(FormatNumber(0.000123456), "0.000123");
}

TEST(PageData, JudgesCompareFiguresAgainstTheirTargets) {
  const nlohmann::json compare = {{"heldout_rel_rmse", 0.0118}, {"alpha_within_0_05", 0.81}, {"ndf_rel_l2_median", 0.02},
                                  {"truth", "t"}, {"something_new", 3.0}};
  const std::vector<ReadableMetric> metrics = ReadableMetrics(compare);
  ASSERT_EQ(metrics.size(), 4u);  // numbers only
  for (const ReadableMetric& m : metrics) {
    if (m.key == "heldout_rel_rmse") {
      EXPECT_EQ(m.text, "1.18%");
      EXPECT_EQ(m.met, 1);
      EXPECT_EQ(m.target, "below 5%");
    } else if (m.key == "alpha_within_0_05") {
      EXPECT_EQ(m.met, 0);  // 81% < 90%
    } else if (m.key == "something_new") {
      EXPECT_EQ(m.name, "something_new");
      EXPECT_EQ(m.met, -1);
    }
  }
}

TEST(PageData, CalibrationSummaryReportsDroppedViewsAndLostDots) {
  const testing::TempFolder folder;
  const nlohmann::json calibration = {
      {"camera", {{"fx", 800.0}, {"fy", 801.0}, {"cx", 320.0}, {"cy", 240.0}, {"rms_px", 0.1}, {"lens_model", "narrow"},
                  {"lens_model_because", "the principal point is not determined"},
                  {"views", {{{"source", "board/v00"}, {"used", true}, {"rms_px", 0.1}},
                             {{"source", "board/v01"}, {"used", false}, {"rms_px", 3.0}, {"dropped_because", "rms"}}}}}},
      {"sample_plane", {{"rms_px", 0.2}, {"camera_centre_m", {0.0, -0.1, 0.9}}}},
      {"monitor", {{"residual_rms_mm", 0.02}, {"residual_max_mm", 0.05},
                   {"dots", {{{"monitor_px", {1, 2}}, {"residual_mm", 0.01}}, {{"monitor_px", {3, 4}}, {"residual_mm", -1}}}}}}};
  common::WriteTextAtomically(folder / "calibration.json", calibration.dump(), false);
  std::vector<std::string> doubts;
  const nlohmann::json summary = CalibrationSummary(folder.path(), &doubts);
  EXPECT_EQ(summary["views"].size(), 2u);
  EXPECT_EQ(summary["camera"]["lens_model"], "narrow");
  ASSERT_EQ(doubts.size(), 3u);  // a view dropped, a dot not found, the narrow lens
  EXPECT_NE(doubts[0].find("1 of 2 board views"), std::string::npos) << doubts[0];
  EXPECT_NE(doubts[1].find("1 of 2 dots"), std::string::npos) << doubts[1];

  std::filesystem::create_directories(folder / "other");
  common::WriteTextAtomically(folder / "other" / "calibration.json", "{\"format\": 1}", false);
  try {
    CalibrationSummary(folder / "other", &doubts);
    ADD_FAILURE() << "a calibration without a camera was accepted";
  } catch (const common::Error& e) {
    EXPECT_EQ(e.subject(), (folder / "other" / "calibration.json").string());
  }
}

TEST(PageData, EmbedsTheGltfsBufferAndImagesAsDataUris) {
  const testing::TempFolder folder;
  common::WriteTextAtomically(folder / "m.bin", std::string("\x01\x02\x03", 3), false);
  common::WriteTextAtomically(folder / "m.png", "PNG", false);
  const nlohmann::json gltf = {{"asset", {{"version", "2.0"}}}, {"buffers", {{{"uri", "m.bin"}, {"byteLength", 3}}}},
                               {"images", {{{"uri", "m.png"}}}}};
  common::WriteTextAtomically(folder / "m.gltf", gltf.dump(), false);
  const nlohmann::json embedded = nlohmann::json::parse(EmbeddedGltf(folder / "m.gltf"));
  EXPECT_EQ(embedded["buffers"][0]["uri"], "data:application/octet-stream;base64,AQID");
  EXPECT_EQ(embedded["images"][0]["uri"], "data:image/png;base64,UE5H");
  EXPECT_EQ(embedded["asset"], gltf["asset"]);
  std::filesystem::remove(folder / "m.png");
  EXPECT_THROW(EmbeddedGltf(folder / "m.gltf"), common::Error);
}

}  // namespace
}  // namespace svbtdf::report
