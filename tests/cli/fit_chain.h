#pragma once
// Test fixture: a `small` simulated session calibrated with its true rig and processed once per
// build (SharedTestData); FitAndCompare runs `svbtdf fit` and `svbtdf compare` on it.
// SVBTDF_FIT_CHAIN_SIMULATE="--preset demo" (or "--preset small --truth montecarlo") runs the same
// fits on another session, for the one-off measurements in docs/validation.md; the tests' bounds
// are stated for the default, "--preset small".
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <nlohmann/json.hpp>

#include "run_command.h"
#include "shared_test_data.h"
#include "svbtdf/common/atomic_file.h"
#include "temp_folder.h"
#include "truth_calibration.h"

namespace svbtdf {
namespace fs = std::filesystem;
using testing::RunSvbtdf;

class FitChain : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    folder_ = std::make_unique<testing::TempFolder>("fitchain");
    root_ = folder_->path();
    const char* simulation = std::getenv("SVBTDF_FIT_CHAIN_SIMULATE");
    const std::string simulate = "simulate " + std::string(simulation ? simulation : "--preset small");
    // Simulated, calibrated and processed once for all of the program's tests (ctest runs each in
    // a process of its own).
    session_ = testing::SharedTestData("fitchain", simulate, [&](const fs::path& shared) {
      const auto simulated = RunSvbtdf(simulate + " --out " + (shared / "sim").string());
      ASSERT_EQ(simulated.exit_code, 0) << simulated.output;
      calib::WriteSessionCalibration(shared / "sim" / "session" / "calibration.json",
                                     CalibrationFromTruth(shared / "sim"));
      const auto processed = RunSvbtdf("process " + (shared / "sim" / "session").string() + " --out " +
                                       (shared / "processed").string());
      ASSERT_EQ(processed.exit_code, 0) << processed.output;
    });
  }
  // SVBTDF_KEEP_TEST_FILES=1 keeps the fitted materials for a look afterwards (the shared session
  // and store stay in the test program's shared-test-data/ folder anyway).
  static void TearDownTestSuite() {
    if (std::getenv("SVBTDF_KEEP_TEST_FILES")) std::printf("kept %s\n", root_.c_str());
    folder_.reset();
  }
  static std::string Processed() { return (session_ / "processed").string(); }
  static fs::path Truth() { return session_ / "sim" / "truth"; }

  static nlohmann::json FitAndCompare(const std::string& name, const std::string& fit_options) {
    const auto fitted = RunSvbtdf("fit " + Processed() + " --out " + (root_ / name).string() + " " + fit_options);
    EXPECT_EQ(fitted.exit_code, 0) << fitted.output;
    const fs::path json = root_ / (name + ".json");
    const auto compared = RunSvbtdf("compare " + (root_ / name).string() + " " + Truth().string() +
                                    " --json " + json.string());
    EXPECT_EQ(compared.exit_code, 0) << compared.output;
    const nlohmann::json metrics = nlohmann::json::parse(common::ReadTextFile(json));
    std::printf("%s: %s\n", name.c_str(), metrics.dump().c_str());
    return metrics;
  }

  static inline std::unique_ptr<testing::TempFolder> folder_;
  static inline fs::path root_;     // this process's outputs
  static inline fs::path session_;  // the shared session and its store
};

}  // namespace svbtdf
