// The pipeline in its one order (process::RunPipeline, `svbtdf run`): on the tiny simulated
// session it calibrates, processes and fits in that order, records every stage's warnings in
// quality.json, reuses a finished calibration and store on a second run, and never overwrites a
// material.

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "svbtdf/acquire/simulated_session.h"
#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/process/pipeline.h"
#include "expect_error.h"
#include "svbtdf/fit/slice_store.h"
#include "temp_folder.h"

namespace svbtdf::process {
namespace {
namespace fs = std::filesystem;

class Pipeline : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { folder_ = std::make_unique<svbtdf::testing::TempFolder>("pipeline"); }
  // The tiny simulated session, made by the first test that needs it (each test runs in a
  // process of its own under ctest: the others do not pay for it).
  static void Simulate() {
    if (fs::exists(folder_->path() / "sim" / "session" / "journal.jsonl")) return;
    simulate::SimulationOptions simulation;
    simulation.progress = false;
    acquire::SimulateSession(folder_->path() / "sim", simulation);
  }
  static void TearDownTestSuite() { folder_.reset(); }

  static PipelineOptions Options(const std::string& out) {
    PipelineOptions options;
    options.session = folder_->path() / "sim" / "session";
    options.out = folder_->path() / out;
    options.work = folder_->path() / "work";
    options.process.progress = false;
    options.fit.progress = false;
    options.fit.threads = 2;
    return options;
  }
  // Runs the pipeline, keeping what it said and warned.
  PipelineOutcome Run(const PipelineOptions& options) {
    lines_.clear();
    warned_.clear();
    PipelineListener listener;
    listener.say = [this](const std::string& line) { lines_.push_back(line); };
    listener.warn = [this](const std::vector<fit::QualityWarning>& w) { warned_.insert(warned_.end(), w.begin(), w.end()); };
    return RunPipeline(options, listener);
  }
  size_t LineStarting(const std::string& prefix) const {
    const auto it = std::find_if(lines_.begin(), lines_.end(),
                                 [&](const std::string& line) { return line.rfind(prefix, 0) == 0; });
    return static_cast<size_t>(it - lines_.begin());
  }

  static inline std::unique_ptr<svbtdf::testing::TempFolder> folder_;
  std::vector<std::string> lines_;
  std::vector<fit::QualityWarning> warned_;
};

TEST_F(Pipeline, CalibratesProcessesAndFitsInOrderThenReusesTheFinishedSteps) {
  Simulate();
  const PipelineOutcome first = Run(Options("first"));
  EXPECT_EQ(first.work, folder_->path() / "work");
  EXPECT_LT(LineStarting("== 1/3 calibrating"), LineStarting("== 2/3 processing into"));
  EXPECT_LT(LineStarting("== 2/3 processing into"), LineStarting("== 3/3 fitting"));
  EXPECT_LT(LineStarting("== 3/3 fitting"), LineStarting("material: "));
  ASSERT_LT(LineStarting("material: "), lines_.size());
  EXPECT_TRUE(fs::exists(folder_->path() / "sim" / "session" / "calibration.json"));
  EXPECT_TRUE(fs::exists(folder_->path() / "first" / "material.json"));
  EXPECT_FALSE(fs::exists(FitCheckpointPath(folder_->path() / "first")));  // removed once written
  // quality.json holds exactly the warnings the stages reported, in order.
  const nlohmann::json quality = nlohmann::json::parse(common::ReadTextFile(folder_->path() / "first" / "quality.json"));
  ASSERT_EQ(quality.at("warnings").size(), first.warnings.size()) << quality.dump(1);
  ASSERT_EQ(warned_.size(), first.warnings.size());
  for (size_t k = 0; k < warned_.size(); ++k) EXPECT_EQ(warned_[k].Line(), first.warnings[k].Line());

  const auto calibration_time = fs::last_write_time(folder_->path() / "sim" / "session" / "calibration.json");
  Run(Options("second"));
  EXPECT_LT(LineStarting("== 1/3 calibration: using"), lines_.size());
  EXPECT_LT(LineStarting("== 2/3 processing: using"), lines_.size());
  EXPECT_EQ(fs::last_write_time(folder_->path() / "sim" / "session" / "calibration.json"), calibration_time);
  EXPECT_TRUE(fs::exists(folder_->path() / "second" / "material.json"));
}

// Issue 15: `--out mat/` put the checkpoint and the work folder inside mat/, and then refused
// mat/ as not empty, so `svbtdf run ... --out mat/` always failed.
TEST_F(Pipeline, ATrailingSlashOnTheOutputNamesTheSameFolder) {
  EXPECT_EQ(FitCheckpointPath("a/mat/"), fs::path("a/mat.partial-fits.jsonl"));
  EXPECT_EQ(FitCheckpointPath("a/mat//"), FitCheckpointPath("a/mat"));
  Simulate();
  PipelineOptions options = Options("slashed/");
  options.work.clear();  // the default, MATERIAL.work
  const PipelineOutcome outcome = Run(options);
  EXPECT_EQ(outcome.work, folder_->path() / "slashed.work");
  EXPECT_TRUE(fs::exists(folder_->path() / "slashed" / "material.json"));
  for (const auto& entry : fs::directory_iterator(folder_->path() / "slashed")) {
    EXPECT_EQ(entry.path().filename().string().find(".work"), std::string::npos) << entry.path();
    EXPECT_EQ(entry.path().filename().string().find("partial-fits"), std::string::npos) << entry.path();
  }
}

TEST_F(Pipeline, ANonEmptyOutputIsRefusedBeforeAnyStep) {
  const fs::path out = folder_->path() / "mine";
  fs::create_directories(out);
  std::ofstream(out / "notes.txt") << "keep\n";
  PipelineOptions options = Options("mine");
  options.work = folder_->path() / "untouched";
  try {
    Run(options);
    ADD_FAILURE() << "not refused";
  } catch (const common::Error& e) {
    EXPECT_EQ(e.kind(), common::ErrorKind::kInvalidInput);
    EXPECT_NE(std::string(e.what()).find(out.string()), std::string::npos) << e.what();
  }
  EXPECT_TRUE(lines_.empty());
  EXPECT_FALSE(fs::exists(options.work));
  EXPECT_EQ(common::ReadTextFile(out / "notes.txt"), "keep\n");
}

TEST_F(Pipeline, AnIncompleteSessionIsRefusedNamingIt) {
  Simulate();
  const fs::path session = folder_->path() / "partial" / "session";
  fs::create_directories(session);
  for (const auto& entry : fs::directory_iterator(folder_->path() / "sim" / "session")) {
    if (entry.is_regular_file() && entry.path().filename() != "journal.jsonl" &&
        entry.path().filename() != "calibration.json") {
      fs::copy_file(entry.path(), session / entry.path().filename());
    }
  }
  PipelineOptions options = Options("from_partial");
  options.session = session;
  try {
    Run(options);
    ADD_FAILURE() << "not refused";
  } catch (const common::Error& e) {
    EXPECT_NE(std::string(e.what()).find("not a complete session"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(session.string()), std::string::npos) << e.what();
  }
}

TEST_F(Pipeline, TheCalibrateAndProcessStagesOfTheCommandsRefuseAnUncalibratedSessionThenRun) {
  Simulate();
  const fs::path session = folder_->path() / "uncalibrated" / "session";
  fs::create_directories(session.parent_path());
  fs::copy(folder_->path() / "sim" / "session", session, fs::copy_options::recursive);
  fs::remove(session / "calibration.json");
  ProcessOptions process;
  process.progress = false;
  svbtdf::testing::ExpectError(common::ErrorKind::kInvalidInput, session.string() + ": has no calibration.json",
                               [&] { ProcessAndCheck(session, folder_->path() / "early", process); });
  calib::CalibrateSessionOptions calibrate;
  calibrate.progress = false;
  const CalibrationStage calibrated = CalibrateAndCheck(session, calibrate);
  EXPECT_EQ(calibrated.file, session / "calibration.json");
  EXPECT_TRUE(fs::exists(calibrated.file));
  EXPECT_GT(calibrated.calibration.camera.camera.fx, 0);
  const ProcessStage processed = ProcessAndCheck(session, folder_->path() / "uncalibrated" / "processed", process);
  EXPECT_GT(processed.report.valid_texels, 0);
  EXPECT_NO_THROW(fit::SliceStore::Open(folder_->path() / "uncalibrated" / "processed"));
}

}  // namespace
}  // namespace svbtdf::process
