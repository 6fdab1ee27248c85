// `svbtdf simulate` end to end: the tiny preset writes a complete session and the truth (demo:
// cmd_simulate_slow_test.cc); an interrupted run resumes to the same images; bad output folders are refused.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>
#include <vector>

#include "run_command.h"
#include "svbtdf/common/atomic_file.h"
#include "svbtdf/session/session.h"
#include "temp_folder.h"

namespace svbtdf {
namespace {
namespace fs = std::filesystem;
using testing::RunSvbtdf;

class SimulateCommand : public ::testing::Test {
 protected:
  testing::TempFolder folder_;
  const fs::path root_ = folder_.path();
};

// `map` is one of the truth's maps: alpha.exr for the analytic truth, slices.exr for Monte Carlo.
void ExpectCompleteSimulation(const fs::path& out, const char* map = "alpha.exr") {
  const session::Session session = session::Session::Open(out / "session");
  const session::SessionVerification verification = session.Verify();
  EXPECT_TRUE(verification.complete()) << verification.Summary();
  const nlohmann::json rig = nlohmann::json::parse(common::ReadTextFile(out / "truth" / "rig.json"));
  for (const char* key : {"fx", "fy", "cx", "cy", "distortion", "rms_px"}) {
    EXPECT_TRUE(rig["camera"].contains(key)) << key;
  }
  EXPECT_TRUE(fs::exists(out / "truth" / "material.json"));
  EXPECT_TRUE(fs::exists(out / "truth" / map));
}

TEST_F(SimulateCommand, TinyPresetWritesACompleteSessionAndNeverOverwritesIt) {
  const fs::path out = root_ / "tiny";
  const auto first = RunSvbtdf("-q simulate --preset tiny --out " + out.string());
  ASSERT_EQ(first.exit_code, 0) << first.output;
  ExpectCompleteSimulation(out);
  // A rerun of the same settings is done already (exit 0, as acquire's); of others, refused.
  const auto journal_time = fs::last_write_time(out / "session" / "journal.jsonl");
  const auto again = RunSvbtdf("-q simulate --preset tiny --out " + out.string());
  EXPECT_EQ(again.exit_code, 0) << again.output;
  EXPECT_NE(again.output.find("already complete"), std::string::npos) << again.output;
  const auto other_seed = RunSvbtdf("-q simulate --preset tiny --seed 9 --out " + out.string());
  EXPECT_EQ(other_seed.exit_code, 2) << other_seed.output;
  EXPECT_NE(other_seed.output.find("never overwritten"), std::string::npos) << other_seed.output;
  EXPECT_EQ(fs::last_write_time(out / "session" / "journal.jsonl"), journal_time);
  // --decode decodes every image as well: the intact session passes it.
  EXPECT_EQ(RunSvbtdf("session verify --decode " + (out / "session").string()).exit_code, 0);
  // `session verify` accepts the session, then names a damaged image and exits 3.
  EXPECT_EQ(RunSvbtdf("session verify " + (out / "session").string()).exit_code, 0);
  fs::remove(out / "session" / session::Session::FileForKey("dot/q0003/e0/r0"));
  const auto verify = RunSvbtdf("session verify " + (out / "session").string());
  EXPECT_EQ(verify.exit_code, 3) << verify.output;
  EXPECT_NE(verify.output.find("dot/q0003/e0/r0"), std::string::npos) << verify.output;
  // Simulating into it again cannot mend it (the journal is append-only): a clear refusal.
  const auto resume = RunSvbtdf("-q simulate --preset tiny --out " + out.string());
  EXPECT_EQ(resume.exit_code, 2) << resume.output;
  EXPECT_NE(resume.output.find("cannot be resumed"), std::string::npos) << resume.output;
  EXPECT_NE(resume.output.find("dot/q0003/e0/r0"), std::string::npos) << resume.output;
}

// Runs the tiny preset whole and interrupted-then-resumed with `arguments` (a vector of extra
// arguments); the two sessions must hold the same images.
void ExpectInterruptedRunResumes(const fs::path& root, const std::vector<std::string>& arguments, const char* map) {
  const fs::path whole = root / "whole", resumed = root / "resumed";
  std::string joined;
  for (const std::string& a : arguments) joined += " " + a;
  ASSERT_EQ(RunSvbtdf("-q simulate" + joined + " --out " + whole.string()).exit_code, 0);
  // Start the same simulation, interrupt it once some images are journalled, then resume.
  const pid_t child = ::fork();
  if (child == 0) {
    std::vector<const char*> argv = {SVBTDF_CLI_PATH, "-q", "simulate"};
    for (const std::string& a : arguments) argv.push_back(a.c_str());
    for (const char* a : {"--out", resumed.c_str()}) argv.push_back(a);
    argv.push_back(nullptr);
    ::execv(SVBTDF_CLI_PATH, const_cast<char* const*>(argv.data()));
    ::_exit(127);
  }
  const fs::path journal = resumed / "session" / "journal.jsonl";
  for (int wait = 0; wait < 12000; ++wait) {
    if (fs::exists(journal) && fs::file_size(journal) > 2000) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ::kill(child, SIGINT);
  int status = 0;
  ::waitpid(child, &status, 0);
  const size_t journalled = session::Session::Open(resumed / "session").entries().size();
  EXPECT_GT(journalled, 0u);
  const auto resume = RunSvbtdf("-q simulate" + joined + " --out " + resumed.string());
  ASSERT_EQ(resume.exit_code, 0) << resume.output;
  ExpectCompleteSimulation(resumed, map);
  const session::Session a = session::Session::Open(whole / "session"), b = session::Session::Open(resumed / "session");
  ASSERT_EQ(a.entries().size(), b.entries().size());
  for (const session::SessionEntry& entry : a.entries()) {
    EXPECT_EQ(entry.crc32, b.Entry(entry.key).crc32) << entry.key;
  }
}

TEST_F(SimulateCommand, AnInterruptedRunResumesToTheSameImages) {
  ExpectInterruptedRunResumes(root_, {"--preset", "tiny", "--seed", "5"}, "alpha.exr");
}

TEST_F(SimulateCommand, BadArgumentsAndFoldersAreClearErrors) {
  fs::create_directories(root_ / "busy");
  common::WriteTextAtomically(root_ / "busy" / "notes.txt", "mine");
  for (const std::string& arguments :
       {"simulate --preset nope --out " + (root_ / "x").string(), "simulate --preset tiny --out " + (root_ / "busy").string(),
        "simulate --preset tiny --eta 0.9 --out " + (root_ / "y").string(), std::string("simulate --preset tiny"),
        "simulate --preset tiny --dots 20 --out " + (root_ / "z").string(),
        "simulate --preset tiny --dots 1x20 --out " + (root_ / "z").string()}) {
    const auto result = RunSvbtdf(arguments);
    EXPECT_EQ(result.exit_code, 2) << arguments << "\n" << result.output;
    EXPECT_NE(result.output.find("svbtdf: error: "), std::string::npos) << result.output;
  }
  EXPECT_EQ(common::ReadTextFile(root_ / "busy" / "notes.txt"), "mine");
}

// `--monitor-polarization`: a bad spec, or a polarised Monte Carlo truth, is one line naming the
// option, exit 2, before anything is written.
TEST_F(SimulateCommand, BadMonitorPolarisationsAreClearErrors) {
  for (const std::string& option : {std::string("--monitor-polarization linear:north"),
                                    std::string("--monitor-polarization circular"),
                                    std::string("--monitor-polarisation linear:45 --truth montecarlo")}) {
    const fs::path out = root_ / "polarised";
    const auto result = RunSvbtdf("simulate --preset tiny " + option + " --out " + out.string());
    EXPECT_EQ(result.exit_code, 2) << option << "\n" << result.output;
    EXPECT_NE(result.output.find("--monitor-polarization"), std::string::npos) << result.output;
    EXPECT_FALSE(fs::exists(out / "session" / "journal.jsonl")) << option;
  }
}

}  // namespace
}  // namespace svbtdf
