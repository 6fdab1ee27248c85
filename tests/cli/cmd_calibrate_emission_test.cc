// `svbtdf calibrate-emission` end to end, the user's path: a diffuser session simulated on a cos^3
// LCD (`simulate --monitor-emission lcd:3 --pattern diffuser`), calibrated from its own captures,
// its profile measured, then used by `process --emission-profile`; bad profiles and options refused.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>

#include "run_command.h"
#include "svbtdf/calib/emission_profile.h"
#include "svbtdf/calib/session_calibration.h"
#include "svbtdf/common/atomic_file.h"
#include "temp_folder.h"

namespace svbtdf {
namespace {
namespace fs = std::filesystem;
using testing::RunSvbtdf;

TEST(CalibrateEmissionCommand, MeasuresAnLcdFromADiffuserSessionAndProcessUsesIt) {
  const testing::TempFolder folder;
  const fs::path sim = folder.path() / "diffuser", profile = folder.path() / "lcd3.json";
  const auto simulated =
      RunSvbtdf("-q simulate --preset tiny --monitor-emission lcd:3 --pattern diffuser --out " + sim.string());
  ASSERT_EQ(simulated.exit_code, 0) << simulated.output;
  const auto measured = RunSvbtdf("-q calibrate-emission " + (sim / "session").string() + " --out " + profile.string());
  ASSERT_EQ(measured.exit_code, 0) << measured.output;
  EXPECT_NE(measured.output.find("best single cos^n: n = "), std::string::npos) << measured.output;
  EXPECT_TRUE(fs::exists(sim / "session" / "calibration.json"));  // calibrated on the way
  const calib::EmissionProfile p = calib::ReadEmissionProfileFile(profile);
  for (double theta = p.covered_min_deg; theta <= p.covered_max_deg; theta += 0.5) {
    EXPECT_NEAR(p.AtDegrees(theta) / std::pow(std::cos(theta * std::numbers::pi / 180), 3.0), 1.0, 0.02) << theta;
  }
  EXPECT_GE(p.covered_max_deg, 46.0);
  EXPECT_NEAR(p.exponent, 3.0, 0.1);

  // process uses it, and the store's calibration records it.
  const fs::path processed = folder.path() / "processed";
  const auto process = RunSvbtdf("-q process " + (sim / "session").string() + " --out " + processed.string() +
                                 " --emission-profile " + profile.string());
  ASSERT_EQ(process.exit_code, 0) << process.output;
  const calib::SessionCalibration used = calib::ReadSessionCalibration(processed / "calibration.json");
  EXPECT_EQ(used.monitor.emission.table, p.table);
  // `run` whose work folder holds a store processed with the profile, but not given the profile,
  // must not fit samples made under another emission than the one it was asked for: refused.
  const fs::path work = folder.path() / "work";
  const auto with_profile = RunSvbtdf("-q process " + (sim / "session").string() + " --out " + (work / "processed").string() +
                                      " --emission-profile " + profile.string());
  ASSERT_EQ(with_profile.exit_code, 0) << with_profile.output;
  const auto mismatched = RunSvbtdf("-q run " + (sim / "session").string() + " --out " +
                                    (folder.path() / "material").string() + " --work " + work.string());
  EXPECT_EQ(mismatched.exit_code, 2) << mismatched.output;
  EXPECT_NE(mismatched.output.find("another monitor emission profile"), std::string::npos) << mismatched.output;
  EXPECT_FALSE(fs::exists(folder.path() / "material"));

  // A damaged profile is one line naming it, exit 2, before anything is written.
  const fs::path bad = folder.path() / "bad.json";
  std::string text = common::ReadTextFile(profile);
  text.replace(text.find("\"step_deg\": 2.0"), 15, "\"step_deg\": -2.0");
  common::WriteTextAtomically(bad, text);
  const auto refused = RunSvbtdf("-q process " + (sim / "session").string() + " --out " +
                                 (folder.path() / "p2").string() + " --emission-profile " + bad.string());
  EXPECT_EQ(refused.exit_code, 2) << refused.output;
  EXPECT_NE(refused.output.find(bad.string() + ": has emission_profile.step_deg"), std::string::npos) << refused.output;
  EXPECT_FALSE(fs::exists(folder.path() / "p2"));
  const auto bad_option = RunSvbtdf("-q simulate --preset tiny --monitor-emission lcd:x --out " +
                                    (folder.path() / "x").string());
  EXPECT_EQ(bad_option.exit_code, 2) << bad_option.output;
  EXPECT_NE(bad_option.output.find("--monitor-emission"), std::string::npos) << bad_option.output;
}

}  // namespace
}  // namespace svbtdf
