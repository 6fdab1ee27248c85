// `svbtdf plan` and `svbtdf simulate --plan PLAN --rig RIG` end to end: a preset's forecast, a
// lab's own plan rendered on its own rig description and calibrated back to that rig, and bad
// plan or rig files as one line naming the file and the field.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>

#include "run_command.h"
#include "svbtdf/acquire/capture_plan.h"
#include "svbtdf/common/atomic_file.h"
#include "svbtdf/session/session.h"
#include "temp_folder.h"

namespace svbtdf {
namespace {
namespace fs = std::filesystem;
using testing::RunSvbtdf;

class PlanCommand : public ::testing::Test {
 protected:
  fs::path Write(const std::string& name, const std::string& text) {
    const fs::path path = root_ / name;
    std::ofstream(path) << text;
    return path;
  }
  // A lab's plan: 3 x 3 of the tiny preset's dots (the inner ones), brackets of 20 and 320 ms,
  // four board views.
  fs::path LabPlan() {
    acquire::CapturePlan plan = acquire::MakePlanPreset("tiny");
    std::vector<std::pair<double, double>> dots;
    for (int row : {1, 2, 4}) {
      for (int col : {1, 3, 4}) dots.push_back(plan.dots_px[row * plan.dot_cols + col]);
    }
    plan.name = "lab-subset";
    plan.dot_cols = plan.dot_rows = 3;
    plan.dots_px = dots;
    plan.exposures_s = {0.02, 0.32};
    plan.board_exposure_s = plan.all_dots_exposure_s = plan.flat_white_exposure_s = 0.01;
    plan.board_views = 4;
    return Write("plan.json", acquire::CapturePlanToJson(plan).dump(1));
  }
  testing::TempFolder folder_;
  const fs::path root_ = folder_.path();
};

TEST_F(PlanCommand, APresetsForecastCountsItsCaptures) {
  const auto result = RunSvbtdf("plan --preset tiny --roughness 0.05,0.3");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const size_t images = acquire::ExpandPlan(acquire::MakePlanPreset("tiny")).size();
  EXPECT_NE(result.output.find("images:    " + std::to_string(images) + " "), std::string::npos) << result.output;
  for (const char* part : {"duration:", "disk:", "centre", "corner (+x, -y)", "a GGX 0.05 lobe spans", "a GGX 0.3 lobe"}) {
    EXPECT_NE(result.output.find(part), std::string::npos) << part << "\n" << result.output;
  }
}

TEST_F(PlanCommand, BadPlanRigAndArgumentsAreOneLineNamingThem) {
  const fs::path rig = Write("rig.json", R"({"format": "svbtdf-rig", "version": 1, "monitor": {"distanse_mm": 40}})");
  const fs::path plan = Write("bad-plan.json", R"({"format": "svbtdf-capture-plan", "version": 1, "dots": 3})");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"plan --rig " + rig.string(), "monitor.distanse_mm"},
      {"plan --plan " + plan.string(), "bad-plan.json"},
      {"plan --preset tiny --roughness 0", "--roughness"},
      {"plan --preset tiny --frame-time -1", "--frame-time"},
      {"simulate --rig " + rig.string() + " --out " + (root_ / "x").string(), "monitor.distanse_mm"},
      {"simulate --plan " + plan.string() + " --preset tiny --out " + (root_ / "y").string(), "bad-plan.json"},
  };
  for (const auto& [arguments, named] : cases) {
    const auto result = RunSvbtdf(arguments);
    EXPECT_EQ(result.exit_code, 2) << arguments << "\n" << result.output;
    EXPECT_NE(result.output.find(named), std::string::npos) << arguments << "\n" << result.output;
    EXPECT_EQ(std::count(result.output.begin(), result.output.end(), '\n'), 1) << result.output;
  }
  EXPECT_FALSE(fs::exists(root_ / "x"));
  EXPECT_FALSE(fs::exists(root_ / "y"));
}

// The lab's rig puts the monitor 44 mm behind the sample, not the preset's 40: calibrating the
// simulated session must find it there, and every dot of the plan.
TEST_F(PlanCommand, ALabsPlanIsSimulatedOnItsOwnRigAndCalibratesBackToIt) {
  const fs::path plan = LabPlan();
  const fs::path rig = Write("rig.json", R"({"format": "svbtdf-rig", "version": 1, "preset": "tiny",
                                             "monitor": {"distance_mm": 44}, "camera": {"frame_time_s": 0.04}})");
  const fs::path out = root_ / "sim";
  const auto forecast = RunSvbtdf("plan --plan " + plan.string() + " --rig " + rig.string());
  ASSERT_EQ(forecast.exit_code, 0) << forecast.output;
  const auto simulated = RunSvbtdf("-q simulate --plan " + plan.string() + " --rig " + rig.string() + " --out " + out.string());
  ASSERT_EQ(simulated.exit_code, 0) << simulated.output;
  const session::Session session = session::Session::Open(out / "session");
  EXPECT_TRUE(session.Verify().complete());
  const acquire::CapturePlan read = acquire::ReadCapturePlan(plan);
  EXPECT_EQ(session.entries().size(), acquire::ExpandPlan(read).size());
  // The forecast counted the same images.
  EXPECT_NE(forecast.output.find("images:    " + std::to_string(session.entries().size()) + " "), std::string::npos)
      << forecast.output;
  EXPECT_EQ(session.rig().acquisition_plan.at("dots"), acquire::CapturePlanToJson(read).at("dots"));
  // The brackets keep their ratio, the shortest becoming the simulator's base exposure.
  const std::vector<double> exposures = session.rig().exposures_s;
  ASSERT_EQ(exposures.size(), 2u);
  EXPECT_NEAR(exposures[1] / exposures[0], 16.0, 1e-9);
  const nlohmann::json notes = session.rig_json().at("simulated");
  EXPECT_EQ(notes.at("rig"), rig.string());
  EXPECT_EQ(notes.at("plan"), "lab-subset");

  const auto calibrated = RunSvbtdf("calibrate " + (out / "session").string());
  ASSERT_EQ(calibrated.exit_code, 0) << calibrated.output;
  std::smatch m;
  const std::regex monitor(R"(monitor: ([0-9.]+) mm behind the sample; (\d+) of (\d+) dots found)");
  ASSERT_TRUE(std::regex_search(calibrated.output, m, monitor)) << calibrated.output;
  EXPECT_NEAR(std::stod(m[1]), 44.0, 1.0);
  EXPECT_EQ(m[2], "9");
  EXPECT_EQ(m[3], "9");

  // Finished: the same command is done already; another plan is refused.
  const auto again = RunSvbtdf("-q simulate --plan " + plan.string() + " --rig " + rig.string() + " --out " + out.string());
  EXPECT_EQ(again.exit_code, 0) << again.output;
  EXPECT_NE(again.output.find("already complete"), std::string::npos) << again.output;
  const auto preset_only = RunSvbtdf("-q simulate --preset tiny --out " + out.string());
  EXPECT_EQ(preset_only.exit_code, 2) << preset_only.output;
}

}  // namespace
}  // namespace svbtdf
