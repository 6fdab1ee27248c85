// `svbtdf acquire` end to end on the simulated rig (sim camera + sim display): a tiny acquisition
// is a complete session that `session verify` accepts, that holds the simulator's images and that
// `svbtdf run` fits; a
// process killed with SIGKILL mid-capture resumes to a complete session with every key journalled
// once; Ctrl-C stops with exit code 130 and resumes; bad arguments, plans and folders are
// one-line errors with exit code 2.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "run_command.h"
#include "svbtdf/common/atomic_file.h"
#include "svbtdf/session/session.h"
#include "temp_folder.h"

namespace svbtdf {
namespace {
namespace fs = std::filesystem;
using testing::RunSvbtdf;

class AcquireCommand : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto simulate = RunSvbtdf("-q simulate --preset tiny --out " + Sim().string());
    ASSERT_EQ(simulate.exit_code, 0) << simulate.output;
  }
  fs::path Sim() const { return root_ / "sim"; }
  std::string AcquireArgs(const fs::path& out) const {
    return "-q acquire --plan-preset tiny --camera sim:" + Sim().string() + " --display sim --out " + out.string();
  }
  static size_t JournalLines(const fs::path& session) {
    if (!fs::exists(session / "journal.jsonl")) return 0;
    const std::string text = common::ReadTextFile(session / "journal.jsonl");
    return static_cast<size_t>(std::count(text.begin(), text.end(), '\n'));
  }
  // The number of images the tiny plan captures (the simulated session holds all of them).
  size_t PlannedImages() const { return session::Session::Open(Sim() / "session").planned_keys().size(); }
  // Starts `svbtdf acquire` into `out` in a child process and returns once `lines` captures are
  // journalled (or after 8 s), for the test to stop it.
  pid_t StartAcquisitionUntilJournalled(const fs::path& out, size_t lines) const {
    const std::string sim_camera = "sim:" + Sim().string();
    const pid_t child = ::fork();
    if (child == 0) {
      ::execl(SVBTDF_CLI_PATH, SVBTDF_CLI_PATH, "-q", "acquire", "--plan-preset", "tiny", "--camera",
              sim_camera.c_str(), "--display", "sim", "--out", out.c_str(), static_cast<char*>(nullptr));
      ::_exit(127);
    }
    for (int wait = 0; wait < 30000 && JournalLines(out) < lines; ++wait) {  // at most a minute
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    return child;
  }
  testing::TempFolder folder_;
  const fs::path root_ = folder_.path();
};

TEST_F(AcquireCommand, TinyAcquireIsACompleteSessionWithTheSimulatorsImages) {
  const fs::path out = root_ / "acquired";
  const auto start = std::chrono::steady_clock::now();
  const auto result = RunSvbtdf(AcquireArgs(out));
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("acquired " + std::to_string(PlannedImages()) + " images"), std::string::npos)
      << result.output;
  const auto verify = RunSvbtdf("session verify " + out.string());
  EXPECT_EQ(verify.exit_code, 0) << verify.output;
  const session::Session acquired = session::Session::Open(out), simulated = session::Session::Open(Sim() / "session");
  ASSERT_EQ(acquired.planned_keys(), simulated.planned_keys());
  for (const session::SessionEntry& entry : simulated.entries()) {
    EXPECT_EQ(acquired.Entry(entry.key).crc32, entry.crc32) << entry.key;
  }
  std::printf("tiny acquire: %zu images in %.2f s (wall, including start-up)\n", acquired.entries().size(), seconds);
  // Re-running a complete session captures nothing and succeeds.
  const auto again = RunSvbtdf(AcquireArgs(out));
  EXPECT_EQ(again.exit_code, 0) << again.output;
  EXPECT_NE(again.output.find("acquired 0 images"), std::string::npos) << again.output;
}

// What a lab does next: `svbtdf run` calibrates, processes and fits the acquired session, and the
// material compares with the simulator's truth. (The tiny rig's 6 x 6 dots sample the lobes too
// sparsely for the fit's acceptance figures, which the `small` preset checks; this checks that
// the acquired session carries everything the chain needs.)
TEST_F(AcquireCommand, AnAcquiredSessionIsFittedByRun) {
  const fs::path out = root_ / "acquired";
  ASSERT_EQ(RunSvbtdf(AcquireArgs(out)).exit_code, 0);
  const fs::path material = root_ / "material";
  const auto run = RunSvbtdf("-q run " + out.string() + " --out " + material.string() + " --holdout 0.1");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_TRUE(fs::exists(out / "calibration.json"));
  const fs::path metrics_file = root_ / "compare.json";
  const auto compare = RunSvbtdf("compare " + material.string() + " " + (Sim() / "truth").string() + " --json " +
                                 metrics_file.string());
  ASSERT_EQ(compare.exit_code, 0) << compare.output;
  const nlohmann::json metrics = nlohmann::json::parse(common::ReadTextFile(metrics_file));
  std::printf("tiny acquired, run, compared: %s\n", metrics.dump().c_str());
  // Measured: rho_d 1.4%, held-out 23% (a broken chain, a lost factor or a wrong geometry, is
  // off by 100% or more).
  EXPECT_LT(metrics.at("rho_d_rel_error_median").get<double>(), 0.03);
  EXPECT_LT(metrics.at("heldout_rel_rmse").get<double>(), 0.4);
}

TEST_F(AcquireCommand, KilledMidCaptureResumesWithNoMissingDuplicatedOrCorruptImage) {
  const fs::path out = root_ / "killed";
  // Kill it once a good part of the session is journalled, with no chance to clean up.
  const pid_t child = StartAcquisitionUntilJournalled(out, 30);
  ::kill(child, SIGKILL);
  int status = 0;
  ::waitpid(child, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status)) << "the acquisition ended before it was killed";
  const size_t before = session::Session::Open(out).entries().size();
  EXPECT_GE(before, 30u);
  EXPECT_LT(before, PlannedImages());
  const auto resume = RunSvbtdf(AcquireArgs(out));
  ASSERT_EQ(resume.exit_code, 0) << resume.output;
  EXPECT_NE(resume.output.find(std::to_string(before) + " were already there"), std::string::npos) << resume.output;
  EXPECT_EQ(RunSvbtdf("session verify " + out.string()).exit_code, 0);
  // The journal names every planned key exactly once.
  std::map<std::string, int> times;
  std::istringstream lines(common::ReadTextFile(out / "journal.jsonl"));
  for (std::string line; std::getline(lines, line);) {
    if (!line.empty()) ++times[nlohmann::json::parse(line).at("key").get<std::string>()];
  }
  const session::Session session = session::Session::Open(out);
  EXPECT_EQ(times.size(), session.planned_keys().size());
  for (const std::string& key : session.planned_keys()) EXPECT_EQ(times[key], 1) << key;
}

TEST_F(AcquireCommand, CtrlCStopsCleanlyWithExitCode130AndTheRunResumes) {
  const fs::path out = root_ / "interrupted";
  const pid_t child = StartAcquisitionUntilJournalled(out, 20);
  ::kill(child, SIGINT);
  int status = 0;
  ::waitpid(child, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 130);
  const session::Session stopped = session::Session::Open(out);
  EXPECT_LT(stopped.entries().size(), PlannedImages());
  EXPECT_TRUE(stopped.Verify().corrupt.empty());
  const auto resume = RunSvbtdf(AcquireArgs(out));
  ASSERT_EQ(resume.exit_code, 0) << resume.output;
  EXPECT_EQ(RunSvbtdf("session verify " + out.string()).exit_code, 0);
}

TEST_F(AcquireCommand, BadArgumentsPlansAndFoldersAreClearErrors) {
  const std::string sim = "--camera sim:" + Sim().string() + " --display sim";
  const fs::path garbled = root_ / "garbled.json";
  common::WriteTextAtomically(garbled, "{\"format\": \"svbtdf-capture-plan\", \"version\": 1, \"dots\": {\"cols\": 2");
  const fs::path changed = root_ / "changed.json";
  common::WriteTextAtomically(changed, R"({"format": "svbtdf-capture-plan", "version": 1,
    "dots": {"cols": 2, "rows": 2, "pitch": [40, 40], "origin": [600, 400], "radius": 4},
    "exposures_s": [0.01]})");
  const fs::path partial = root_ / "partial";
  // A plan of one's own runs on the simulated rig too (its dots are not the simulation's).
  const auto own = RunSvbtdf("-q acquire --plan " + changed.string() + " " + sim + " --out " + partial.string());
  ASSERT_EQ(own.exit_code, 0) << own.output;
  EXPECT_EQ(RunSvbtdf("session verify " + partial.string()).exit_code, 0);
  // `svbtdf simulate` is this loop on the simulated rig: its session is an acquisition of the tiny
  // plan, which acquire finds complete.
  const auto simulated = RunSvbtdf("-q acquire --plan-preset tiny " + sim + " --out " + (Sim() / "session").string());
  EXPECT_EQ(simulated.exit_code, 0) << simulated.output;
  EXPECT_NE(simulated.output.find("acquired 0 images"), std::string::npos) << simulated.output;
  // A session another program wrote (no acquisition plan in its manifest) is never changed.
  const fs::path foreign = root_ / "foreign";
  session::Session::Create(foreign, {{"camera", {{"model", "someone else's"}}}}, {"dark/e0/r0"});
  struct Case {
    std::string arguments, names;
  };
  const std::vector<Case> cases = {
      {"acquire --plan " + garbled.string() + " " + sim + " --out " + (root_ / "a").string(), garbled.string()},
      {"acquire --plan-preset tiny --camera sim:" + (root_ / "nowhere").string() + " --display sim --out " +
           (root_ / "b").string(), "nowhere"},
      {"acquire --plan-preset tiny --camera webcam --display sim --out " + (root_ / "c").string(), "--camera"},
      {"acquire --plan-preset tiny --camera sim:" + Sim().string() + " --display sdl:0 --out " + (root_ / "d").string(),
       "--display"},
      {"acquire --plan-preset tiny " + sim + " --out " + partial.string(), "different capture plan"},
      {"acquire --plan-preset tiny " + sim + " --out " + foreign.string(), "did not write"},
      {"acquire --plan " + changed.string() + " --plan-preset tiny " + sim + " --out " + (root_ / "e").string(),
       "exactly one"},
  };
  for (const Case& c : cases) {
    const auto result = RunSvbtdf(c.arguments);
    EXPECT_EQ(result.exit_code, 2) << c.arguments << "\n" << result.output;
    EXPECT_NE(result.output.find("svbtdf: error: "), std::string::npos) << result.output;
    EXPECT_NE(result.output.find(c.names), std::string::npos) << c.names << "\n" << result.output;
  }
  EXPECT_FALSE(fs::exists(root_ / "a"));
}

}  // namespace
}  // namespace svbtdf
