// `svbtdf simulate` as the capture loop run on the simulated rig: a complete tiny session whose
// manifest says what was simulated, byte-identical resumption (also in the middle of the dark
// frames, which the simulated camera cannot tell apart by what it sees), Ctrl-C, and refusals.

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "svbtdf/acquire/simulated_session.h"
#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/interrupt.h"
#include "svbtdf/session/session.h"
#include "svbtdf/simulate/capture_render.h"
#include "svbtdf/simulate/simulation.h"
#include "svbtdf/simulate/truth_io.h"
#include "temp_folder.h"

namespace svbtdf::acquire {
namespace {
namespace fs = std::filesystem;

class SimulatedSession : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    folder_ = std::make_unique<svbtdf::testing::TempFolder>("simulated_session");
    Options().progress = false;
  }
  // The uninterrupted tiny simulation, made by the first test that needs it.
  static fs::path Whole() {
    const fs::path whole = folder_->path() / "whole";
    if (!fs::exists(whole / "session" / "journal.jsonl")) {
      const SimulationOutput output = SimulateSession(whole, Options());
      EXPECT_EQ(output.resumed, 0);
      EXPECT_GT(output.images, 0);
    }
    return whole;
  }
  static void TearDownTestSuite() { folder_.reset(); }
  void TearDown() override { common::SetInterruptRequested(false); }

  static simulate::SimulationOptions& Options() {
    static simulate::SimulationOptions options;
    return options;
  }

  // Every planned image of `out` has the bytes (CRC) of the uninterrupted simulation's.
  static void ExpectSameImagesAsTheWholeRun(const fs::path& out) {
    const session::Session whole = session::Session::Open(Whole() / "session");
    const session::Session other = session::Session::Open(out / "session");
    EXPECT_TRUE(other.Verify(/*check_crc=*/true).complete()) << other.Verify().Summary();
    ASSERT_EQ(other.planned_keys(), whole.planned_keys());
    for (const std::string& key : whole.planned_keys()) {
      EXPECT_EQ(other.Entry(key).crc32, whole.Entry(key).crc32) << key;
      EXPECT_EQ(other.Entry(key).exposure_s, whole.Entry(key).exposure_s) << key;
    }
  }

  static inline std::unique_ptr<svbtdf::testing::TempFolder> folder_;
};

TEST_F(SimulatedSession, IsACompleteAcquisitionThatNamesWhatWasSimulated) {
  const session::Session session = session::Session::Open(Whole() / "session");
  EXPECT_TRUE(session.Verify(true).complete());
  const nlohmann::json& rig = session.rig_json();
  EXPECT_EQ(rig.at("simulated").at("preset"), "tiny");
  EXPECT_EQ(rig.at("simulated").at("seed"), 1);
  EXPECT_EQ(rig.at("simulated").at("truth"), "model");
  // The plan the loop ran is recorded, as for any acquisition (a resume must use the same one).
  EXPECT_TRUE(rig.contains("acquisition_plan"));
  EXPECT_TRUE(rig.at("monitor").contains("black_level"));
  EXPECT_TRUE(fs::exists(Whole() / "truth" / "rig.json"));
  EXPECT_TRUE(fs::exists(Whole() / "truth" / "material.json"));
}

TEST_F(SimulatedSession, ResumedBetweenTwoDarkFramesStoresTheUninterruptedBytes) {
  // The state a crash after the first dark frame leaves: its journal line and image only.
  const fs::path out = folder_->path() / "after_one_dark";
  fs::create_directories(out / "session" / "images" / "dark" / "e0");
  fs::copy(Whole() / "truth", out / "truth", fs::copy_options::recursive);
  for (const auto& entry : fs::directory_iterator(Whole() / "session")) {  // the manifest and plan
    if (entry.is_regular_file() && entry.path().filename() != "journal.jsonl") {
      fs::copy_file(entry.path(), out / "session" / entry.path().filename());
    }
  }
  fs::copy_file(Whole() / "session" / "images" / "dark" / "e0" / "r0.png",
                out / "session" / "images" / "dark" / "e0" / "r0.png");
  const std::string journal = common::ReadTextFile(Whole() / "session" / "journal.jsonl");
  const std::string first_line = journal.substr(0, journal.find('\n') + 1);
  ASSERT_NE(first_line.find("\"dark/e0/r0\""), std::string::npos) << first_line;
  std::ofstream(out / "session" / "journal.jsonl", std::ios::binary) << first_line;

  const SimulationOutput resumed = SimulateSession(out, Options());
  EXPECT_EQ(resumed.resumed, 1);
  // dark/e0/r1 is dark frame 1's noise, not dark frame 0's again.
  ExpectSameImagesAsTheWholeRun(out);
}

TEST_F(SimulatedSession, CtrlCLeavesAResumableSessionWithTheSameBytes) {
  const fs::path out = folder_->path() / "interrupted";
  std::atomic<bool> done = false;
  std::thread interrupter([&] {  // Ctrl-C once a few images are journalled
    const fs::path journal = out / "session" / "journal.jsonl";
    while (!done) {
      std::error_code error;
      if (fs::file_size(journal, error) > 600 && !error) {
        common::SetInterruptRequested(true);
        return;
      }
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
  });
  try {
    SimulateSession(out, Options());
    ADD_FAILURE() << "the interrupt was not noticed";
  } catch (const common::Error& e) {
    EXPECT_EQ(e.kind(), common::ErrorKind::kInterrupted) << e.what();
  }
  done = true;
  interrupter.join();
  common::SetInterruptRequested(false);
  const SimulationOutput resumed = SimulateSession(out, Options());
  EXPECT_GT(resumed.resumed, 0);
  EXPECT_LT(resumed.resumed, resumed.images);
  ExpectSameImagesAsTheWholeRun(out);
}

TEST_F(SimulatedSession, ACompleteSessionOrAForeignFolderIsNeverTouched) {
  const auto expect_refused = [](const fs::path& out, const std::string& words) {
    try {
      SimulateSession(out, Options());
      ADD_FAILURE() << out << " was not refused";
    } catch (const common::Error& e) {
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(out.string()), std::string::npos) << e.what();
    }
  };
  const auto before = fs::last_write_time(Whole() / "session" / "journal.jsonl");
  const SimulationOutput again = SimulateSession(Whole(), Options());  // the same settings: done already
  EXPECT_TRUE(again.already_complete);
  EXPECT_EQ(again.resumed, again.images);
  simulate::SimulationOptions other_seed = Options();
  other_seed.seed += 1;
  EXPECT_THROW(SimulateSession(Whole(), other_seed), common::Error);
  EXPECT_EQ(fs::last_write_time(Whole() / "session" / "journal.jsonl"), before);
  const fs::path foreign = folder_->path() / "foreign";
  fs::create_directories(foreign);
  std::ofstream(foreign / "notes.txt") << "mine\n";
  expect_refused(foreign, "notes.txt");
}

TEST_F(SimulatedSession, BadOptionsAreRefusedBeforeAnythingIsWritten) {
  simulate::SimulationOptions options = Options();
  options.eta = 0.5;
  const fs::path out = folder_->path() / "bad_eta";
  EXPECT_THROW(SimulateSession(out, options), common::Error);
  EXPECT_FALSE(fs::exists(out));
}

// `svbtdf simulate --monitor-polarization linear:45`: a complete session whose manifest notes
// the polarisation and whose truth records it (and rebuilds it); the dot images change, the
// captures without the sample do not. The unpolarised session notes nothing new.
TEST_F(SimulatedSession, APolarisedScreenIsRecordedInTheSessionAndTheTruth) {
  const fs::path out = folder_->path() / "polarised";
  simulate::SimulationOptions options = Options();
  options.monitor_polarisation = simulate::Polarisation::Parse("linear:45", "--monitor-polarization");
  const SimulationOutput output = SimulateSession(out, options);
  const session::Session session = session::Session::Open(out / "session");
  EXPECT_TRUE(session.Verify(true).complete()) << session.Verify().Summary();
  EXPECT_EQ(session.rig().monitor.polarisation, "linear:45");
  EXPECT_EQ(session.rig_json().at("acquisition_plan").at("rig").at("monitor_polarisation"), "linear:45");
  const simulate::RigTruth truth = simulate::ReadRigTruth(out / "truth" / "rig.json");
  EXPECT_EQ(truth.monitor.polarisation.kind, "linear");
  EXPECT_EQ(truth.monitor.polarisation.angle_deg, 45.0);
  EXPECT_EQ(simulate::LoadSimulatedSetup(out, 1)->preset.rig.monitor.polarisation.angle_deg, 45.0);

  const session::Session whole = session::Session::Open(Whole() / "session");
  EXPECT_TRUE(whole.rig().monitor.polarisation.empty());
  EXPECT_FALSE(simulate::ReadRigTruth(Whole() / "truth" / "rig.json").monitor.polarisation.linear());
  EXPECT_EQ(session.Entry("flat_white/e0").crc32, whole.Entry("flat_white/e0").crc32);
  EXPECT_EQ(session.Entry("board/v00").crc32, whole.Entry("board/v00").crc32);
  int changed = 0;
  for (const std::string& key : whole.planned_keys()) {
    if (key.rfind("dot/", 0) == 0) changed += session.Entry(key).crc32 != whole.Entry(key).crc32;
  }
  EXPECT_GT(changed, 0);
  // Run again with the same options: already complete.
  EXPECT_TRUE(SimulateSession(out, options).already_complete);
}

// `svbtdf simulate --dots 4x3`: the preset's rig captured with another dot grid over the same span
// of the screen. The session plans one dot image per dot and bracket, the truth records the grid,
// the simulation rebuilds from it (what `acquire --camera sim:OUT` does), and a rerun is complete.
TEST_F(SimulatedSession, AnotherDotGridSpansTheSameScreen) {
  const fs::path out = folder_->path() / "dots";
  simulate::SimulationOptions options = Options();
  options.dot_cols = 4;
  options.dot_rows = 3;
  SimulateSession(out, options);
  const session::Session session = session::Session::Open(out / "session");
  EXPECT_TRUE(session.Verify(true).complete()) << session.Verify().Summary();
  const simulate::RigTruth truth = simulate::ReadRigTruth(out / "truth" / "rig.json");
  const simulate::RigTruth preset = simulate::ReadRigTruth(Whole() / "truth" / "rig.json");
  ASSERT_EQ(truth.dots.size(), 12u);
  const size_t brackets = truth.capture.dot_exposures_s.size();
  int dot_images = 0;
  for (const std::string& key : session.planned_keys()) dot_images += key.rfind("dot/", 0) == 0;
  EXPECT_EQ(dot_images, static_cast<int>(12 * brackets));
  // The same span: the corner dots of both grids coincide (4 x 3 against the preset's 6 x 6).
  // (within a monitor pixel: dots are drawn on pixel centres).
  EXPECT_LT((truth.dots.front().position - preset.dots.front().position).norm(), 1e-3);
  EXPECT_LT((truth.dots.back().position - preset.dots.back().position).norm(), 1e-3);
  const auto rebuilt = simulate::LoadSimulatedSetup(out, 1);
  EXPECT_EQ(rebuilt->rig->dots().size(), 12u);
  EXPECT_TRUE(SimulateSession(out, options).already_complete);
  options.dot_cols = 1;
  EXPECT_THROW(SimulateSession(folder_->path() / "one_column", options), common::Error);
}

}  // namespace
}  // namespace svbtdf::acquire
