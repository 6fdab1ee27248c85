// The emission profile's vocabulary: evaluation of every kind, the measured table's interpolation
// and tail, its JSON in calibration.json and PROFILE.json, and the readers' refusals.

#include "svbtdf/calib/emission_profile.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <numbers>

#include "expect_error.h"
#include "svbtdf/calib/session_calibration.h"
#include "svbtdf/common/atomic_file.h"
#include "temp_folder.h"

namespace svbtdf::calib {
namespace {

double Cos(double degrees) { return std::cos(degrees * std::numbers::pi / 180.0); }

// A measured table of cos^3 every 5 degrees up to 40.
EmissionProfile Cos3Table() {
  EmissionProfile p;
  p.kind = "measured";
  p.step_deg = 5.0;
  p.exponent = 3.0;
  for (int k = 0; k <= 8; ++k) p.table.push_back(std::pow(Cos(5.0 * k), 3.0));
  p.covered_min_deg = 0.0;
  p.covered_max_deg = 40.0;
  return p;
}

TEST(EmissionProfile, NominalKinds) {
  EmissionProfile p;
  EXPECT_EQ(p(Cos(60)), 1.0);
  p.kind = "lambertian";
  EXPECT_NEAR(p(Cos(60)), 0.5, 1e-12);
  p.kind = "lcd";
  p.exponent = 2.0;
  EXPECT_NEAR(p(Cos(60)), 0.25, 1e-12);
  EXPECT_NEAR(p.AtDegrees(60), 0.25, 1e-12);
}

TEST(EmissionProfile, MeasuredTableIsExactAtNodesLogLinearBetweenAndCosNBeyond) {
  const EmissionProfile p = Cos3Table();
  for (int k = 0; k <= 8; ++k) EXPECT_NEAR(p.AtDegrees(5.0 * k), std::pow(Cos(5.0 * k), 3.0), 1e-12);
  // Halfway between nodes: the geometric mean of the two.
  EXPECT_NEAR(p.AtDegrees(12.5), std::sqrt(p.table[2] * p.table[3]), 1e-12);
  // Between nodes, linear interpolation of ln cos^n errs by at most h^2 / 8 n / cos^2 theta:
  // 0.5% at 40 degrees for 5-degree steps and n = 3.
  for (double theta = 0; theta <= 40; theta += 0.25) {
    const double h = 5.0 * std::numbers::pi / 180.0, bound = h * h / 8 * 3 / (Cos(theta + 5) * Cos(theta + 5));
    EXPECT_NEAR(p.AtDegrees(theta) / std::pow(Cos(theta), 3.0), 1.0, bound) << theta;
  }
  // Beyond the table: the measured cos^n continues it (here exactly cos^3).
  EXPECT_NEAR(p.AtDegrees(60), 0.125, 1e-9);
  EXPECT_NEAR(p(Cos(60)), 0.125, 1e-9);
  EXPECT_NEAR(p.AtDegrees(90), 0.0, 1e-12);
}

TEST(EmissionProfile, CalibrationJsonRoundTripAndVersionOne) {
  SessionCalibration c;
  c.monitor.dots.push_back({});
  c.sample_plane.translation = model::Vec3(0, 0, -1);  // camera above the sample
  c.camera.camera.fx = c.camera.camera.fy = 1000;
  c.camera.camera.width = c.camera.camera.height = 100;
  c.monitor.emission = Cos3Table();
  nlohmann::json json = ToJson(c);
  EXPECT_EQ(json["version"], 2);
  const SessionCalibration back = SessionCalibrationFromJson(json, "calibration.json");
  EXPECT_EQ(back.monitor.emission.kind, "measured");
  EXPECT_EQ(back.monitor.emission.table, c.monitor.emission.table);
  EXPECT_EQ(back.monitor.emission.step_deg, 5.0);
  EXPECT_EQ(back.monitor.emission.covered_max_deg, 40.0);
  EXPECT_EQ(back.monitor.Emission(Cos(20)), c.monitor.Emission(Cos(20)));
  // A version 1 file (before measured profiles) reads as it is.
  c.monitor.emission = EmissionProfile{"lcd", 4.0};
  json = ToJson(c);
  json["version"] = 1;
  json["monitor"].erase("emission_profile");
  EXPECT_NEAR(SessionCalibrationFromJson(json, "old.json").monitor.Emission(Cos(60)), 1.0 / 16, 1e-12);
  json["version"] = 3;
  testing::ExpectError(common::ErrorKind::kFormat, "old.json: has calibration format version 3",
                       [&] { SessionCalibrationFromJson(json, "old.json"); });
}

TEST(EmissionProfile, ReadersRefuseValuesOutsideTheirPhysicalRanges) {
  const auto refused = [](const std::function<void(nlohmann::json&)>& edit, const std::string& text) {
    nlohmann::json monitor = nlohmann::json::object();
    PutEmissionProfile(Cos3Table(), &monitor);
    edit(monitor);
    testing::ExpectError(common::ErrorKind::kFormat, text, [&] { EmissionProfileFromJson(monitor, "c.json"); });
  };
  refused([](nlohmann::json& m) { m["emission"] = "oled"; }, "c.json: has an unknown monitor.emission 'oled'");
  refused([](nlohmann::json& m) { m["emission_exponent"] = -1; }, "emission_exponent");
  refused([](nlohmann::json& m) { m["emission_profile"]["step_deg"] = 0; }, "step_deg");
  refused([](nlohmann::json& m) { m["emission_profile"]["table"][3] = 0.0; }, "table[3]");
  refused([](nlohmann::json& m) { m["emission_profile"]["table"][0] = 0.9; }, "does not start at 1");
  refused([](nlohmann::json& m) { m["emission_profile"]["step_deg"] = 12; }, "reaching 90 degrees");
  refused([](nlohmann::json& m) { m["emission_profile"]["covered_deg"] = {30, 10}; }, "covered_deg");
  refused([](nlohmann::json& m) { m["emission_profile"].erase("table"); }, "malformed");
  refused([](nlohmann::json& m) { m["emission_profile"]["table"] = "flat"; }, "malformed");
}

TEST(EmissionProfile, ProfileFileRoundTripAndRefusals) {
  const testing::TempFolder folder;
  const std::filesystem::path path = folder.path() / "profile.json";
  EmissionFitReport report;
  report.observations = 10;
  report.table_std.assign(9, 0.001);
  WriteEmissionProfileFile(path, Cos3Table(), report, {{"session", "diffuser"}});
  const EmissionProfile back = ReadEmissionProfileFile(path);
  EXPECT_EQ(back.table, Cos3Table().table);
  EXPECT_EQ(back.exponent, 3.0);

  common::WriteTextAtomically(path, R"({"format": "svbtdf-calibration", "version": 2})");
  testing::ExpectError(common::ErrorKind::kFormat, path.string() + ": is not an svbtdf emission profile",
                       [&] { ReadEmissionProfileFile(path); });
  common::WriteTextAtomically(path, R"({"format": "svbtdf-emission-profile", "version": 1,
                                        "monitor": {"emission": "lcd", "emission_exponent": 2}})");
  testing::ExpectError(common::ErrorKind::kFormat, "holds a 'lcd' profile, not a measured one",
                       [&] { ReadEmissionProfileFile(path); });
  common::WriteTextAtomically(path, R"({"format": "svbtdf-emission-profile", "version": 7, "monitor": {}})");
  testing::ExpectError(common::ErrorKind::kFormat, "version 7", [&] { ReadEmissionProfileFile(path); });
}

}  // namespace
}  // namespace svbtdf::calib
