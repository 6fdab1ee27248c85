// Quality warnings on the command line (docs/quality.md): a good `tiny` session calibrates, runs
// and reports without a warning and `run --strict` exits 0; a session whose dots are mislabelled
// draws warnings naming the stage, the file and the figures, `run --strict` exits 4, and the
// report shows the warnings at the top of its page; `fit` checks the store it is given.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "analytic_store.h"
#include "run_command.h"
#include "small_material.h"
#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/image_io.h"
#include "svbtdf/fit/quality.h"
#include "temp_folder.h"

namespace svbtdf {
namespace {
namespace fs = std::filesystem;
using testing::RunSvbtdf;

std::string ReadPage(const fs::path& report) {
  std::stringstream html;
  html << std::ifstream(report / "index.html").rdbuf();
  return html.str();
}

// Each test runs in its own process (gtest_discover_tests): every one that needs the session
// simulates it (about 7 s for `tiny`, 20 s for `small`) and calibrates it.
class QualityCommand : public ::testing::Test {
 protected:
  fs::path Session() const { return root_ / "sim" / "session"; }
  // Simulates the session and runs `calibrate --strict` on it. `tiny`'s 6 x 6 dots are 15 degrees
  // apart, too sparse for its lobes (the process stage's lobe-undersampled warning); `small`'s 20 x 20
  // sample them.
  testing::CommandResult SimulateAndCalibrate(const std::string& preset = "tiny") const {
    const auto simulated = RunSvbtdf("-q simulate --preset " + preset + " --out " + (root_ / "sim").string());
    EXPECT_EQ(simulated.exit_code, 0) << simulated.output;
    return RunSvbtdf("-q calibrate --strict " + Session().string());
  }

  // A copy of the session whose calibration has the dot grid turned by 180 degrees (the monitor
  // mounted upside down): each dot takes the position of dot N-1-q, and its residual is how far
  // that is from where it was seen.
  fs::path MislabelledSession() const {
    const fs::path bad = root_ / "bad-session";
    fs::copy(Session(), bad, fs::copy_options::recursive);
    nlohmann::json calibration = nlohmann::json::parse(common::ReadTextFile(bad / "calibration.json"));
    nlohmann::json& dots = calibration["monitor"]["dots"];
    const nlohmann::json original = dots;
    const size_t n = dots.size();
    double sum = 0, max = 0;
    for (size_t q = 0; q < n; ++q) {
      const auto& from = original[q]["position_m"];
      const auto& to = original[n - 1 - q]["position_m"];
      double d2 = 0;
      for (int k = 0; k < 3; ++k) d2 += std::pow(to[k].get<double>() - from[k].get<double>(), 2);
      const double mm = 1000 * std::sqrt(d2);
      dots[q]["position_m"] = to;
      dots[q]["residual_mm"] = mm;
      sum += mm * mm;
      max = std::max(max, mm);
    }
    calibration["monitor"]["residual_rms_mm"] = std::sqrt(sum / n);
    calibration["monitor"]["residual_max_mm"] = max;
    common::WriteTextAtomically(bad / "calibration.json", calibration.dump(2));
    return bad;
  }

  testing::TempFolder folder_;  // SVBTDF_KEEP_TEST_FILES=1 keeps it
  const fs::path root_ = folder_.path();
};

TEST_F(QualityCommand, AGoodSmallSessionDrawsNoWarningAndRunStrictExitsZero) {
  const auto calibrated = SimulateAndCalibrate("small");
  ASSERT_EQ(calibrated.exit_code, 0) << calibrated.output;
  EXPECT_EQ(calibrated.output.find("warning:"), std::string::npos) << calibrated.output;
  const auto run = RunSvbtdf("-q run --strict " + Session().string() + " --out " + (root_ / "good").string());
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_EQ(run.output.find("warning:"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("quality: no warnings"), std::string::npos) << run.output;
  const nlohmann::json quality = nlohmann::json::parse(common::ReadTextFile(root_ / "good" / "quality.json"));
  EXPECT_EQ(quality["format"], "svbtdf-quality");
  EXPECT_EQ(quality["version"], 1);
  EXPECT_TRUE(quality["warnings"].empty()) << quality.dump(2);
  const auto report = RunSvbtdf("report " + (root_ / "good").string() + " --out " + (root_ / "report").string());
  ASSERT_EQ(report.exit_code, 0) << report.output;
  const std::string page = ReadPage(root_ / "report");
  EXPECT_NE(page.find("Quality checks: no warnings"), std::string::npos);
  EXPECT_EQ(page.find("Quality warnings"), std::string::npos);
}

TEST_F(QualityCommand, MislabelledDotsDrawWarningsRunStrictExitsFourAndTheReportShowsThemFirst) {
  ASSERT_EQ(SimulateAndCalibrate().exit_code, 0);
  const fs::path bad = MislabelledSession();
  const fs::path material = root_ / "bad";
  const auto run = RunSvbtdf("-q run --strict " + bad.string() + " --out " + material.string());
  EXPECT_EQ(run.exit_code, fit::kQualityWarningExitCode) << run.output;
  EXPECT_NE(run.output.find("warning: calibrate: " + (bad / "calibration.json").string() + ": the dots found"),
            std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("likely cause: the dots may be mislabelled (monitor orientation"), std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("warning: fit: " + (material / "residual.exr").string() + ": "), std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("--strict: exit code 4"), std::string::npos) << run.output;
  // The material is still written, with every stage's warnings in pipeline order.
  ASSERT_TRUE(fs::exists(material / "material.json"));
  std::vector<fit::QualityWarning> warnings;
  ASSERT_TRUE(fit::ReadQuality(material, &warnings));
  ASSERT_GE(warnings.size(), 2u);
  EXPECT_EQ(warnings.front().check, "dot-residual");
  EXPECT_EQ(warnings.back().stage, "fit");

  const auto report = RunSvbtdf("report " + material.string() + " --out " + (root_ / "report").string());
  ASSERT_EQ(report.exit_code, 0) << report.output;
  EXPECT_NE(report.output.find("quality warning"), std::string::npos) << report.output;
  const std::string page = ReadPage(root_ / "report");
  const size_t top = page.find("<h2>Quality warnings (" + std::to_string(warnings.size()) + ")");
  ASSERT_NE(top, std::string::npos) << page.substr(0, 3000);
  // First on the page: the first heading after the title, before the material's description.
  EXPECT_EQ(page.find("<h2>"), top);
  EXPECT_LT(top, page.find("Material <code>"));
  EXPECT_NE(page.find("the dots may be mislabelled", top), std::string::npos);
  EXPECT_NE(page.find((material / "residual.exr").string(), top), std::string::npos);
}

TEST_F(QualityCommand, AReportOfAMaterialWithoutQualityJsonChecksTheMaterialItself) {
  // A material written before the checks existed (no quality.json), with one implausible k_s.
  fit::Material material = SmallMaterial();
  material.k_s.at(2, 1, 1) = 1.5e5f;
  fit::WriteMaterial(root_ / "material", material);
  const auto report = RunSvbtdf("report " + (root_ / "material").string() + " --out " + (root_ / "report").string());
  ASSERT_EQ(report.exit_code, 0) << report.output;
  const std::string page = ReadPage(root_ / "report");
  EXPECT_EQ(page.find("<h2>"), page.find("<h2>Quality warnings (1)")) << page.substr(0, 3000);
  EXPECT_NE(page.find("k_s is implausibly large"), std::string::npos);
  EXPECT_NE(page.find("1.5e+05 at texel (2, 1)"), std::string::npos);
  EXPECT_NE(page.find("has no <code>quality.json</code>"), std::string::npos);
}

TEST_F(QualityCommand, FitStrictChecksTheStoreItIsGivenAndRecordsEveryStage) {
  // A store synthesised from a known material (no images): its calibration and maps are good.
  ::svbtdf::testing::WriteAnalyticStore(root_ / "processed", ::svbtdf::testing::AnalyticMaterial{6, 6}, 24, 0.01);
  const auto fitted = RunSvbtdf("-q fit --strict --representatives 0.25 " + (root_ / "processed").string() + " --out " +
                                (root_ / "material").string());
  ASSERT_EQ(fitted.exit_code, 0) << fitted.output;
  EXPECT_EQ(fitted.output.find("warning:"), std::string::npos) << fitted.output;
  std::vector<fit::QualityWarning> warnings;
  ASSERT_TRUE(fit::ReadQuality(root_ / "material", &warnings));
  EXPECT_TRUE(warnings.empty());
  // Its calibration made bad afterwards: `fit` reports the calibration it was given too.
  nlohmann::json calibration = nlohmann::json::parse(common::ReadTextFile(root_ / "processed" / "calibration.json"));
  calibration["camera"]["rms_px"] = 2.5;
  common::WriteTextAtomically(root_ / "processed" / "calibration.json", calibration.dump(2));
  const auto again = RunSvbtdf("-q fit --strict --representatives 0.25 " + (root_ / "processed").string() + " --out " +
                               (root_ / "material2").string());
  EXPECT_EQ(again.exit_code, fit::kQualityWarningExitCode) << again.output;
  EXPECT_NE(again.output.find("warning: calibrate: " + (root_ / "processed" / "calibration.json").string() +
                              ": the camera calibration's reprojection error is high (Zhang reprojection RMS 2.500 px"),
            std::string::npos)
      << again.output;
  ASSERT_TRUE(fit::ReadQuality(root_ / "material2", &warnings));
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0].check, "camera-rms");
}

}  // namespace
}  // namespace svbtdf
