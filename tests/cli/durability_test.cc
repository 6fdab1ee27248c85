// What the commands promise about a user's data (docs/capture.md, "Durability"): a full disk or
// a kill at any write is resumed to the same images as an uninterrupted run, a failed write is
// never journalled, and two commands never write one folder at once.
#include <gtest/gtest.h>
#include <sys/mount.h>
#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <thread>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "run_command.h"
#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/folder_lock.h"
#include "svbtdf/session/session.h"
#include "temp_folder.h"

namespace svbtdf {
namespace {
namespace fs = std::filesystem;
using testing::RunSvbtdf;

// Every image of a session by key, as bytes.
std::map<std::string, std::string> Images(const fs::path& session_folder) {
  std::map<std::string, std::string> images;
  const session::Session session = session::Session::Open(session_folder);
  for (const session::SessionEntry& entry : session.entries()) {
    images[entry.key] = common::ReadTextFile(session_folder / entry.file);
  }
  return images;
}

// No file of the run's temporary names may survive a resume.
int TemporaryFilesUnder(const fs::path& folder) {
  int count = 0;
  for (const auto& entry : fs::recursive_directory_iterator(folder)) {
    count += entry.path().filename().string().find(".tmp-") != std::string::npos;
  }
  return count;
}

class Durability : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    reference_ = new testing::TempFolder();
    const auto run = RunSvbtdf("-q simulate --preset tiny --out " + (reference_->path() / "tiny").string());
    ASSERT_EQ(run.exit_code, 0) << run.output;
    reference_images_ = new std::map<std::string, std::string>(Images(reference_->path() / "tiny" / "session"));
  }
  static void TearDownTestSuite() {
    delete reference_images_;
    delete reference_;
  }

  // Simulates tiny into OUT with the N-th durable operation failing as `action` does, then resumes
  // without faults; the session must be complete, decode, and equal the uninterrupted run's.
  // Returns false when the run had fewer than N durable operations (nothing was injected).
  bool FaultThenResume(int64_t n, const std::string& action) {
    const fs::path out = folder_.path() / (action + std::to_string(n));
    const std::string simulate = "-q simulate --preset tiny --out " + out.string();
    const auto faulted = RunSvbtdf(simulate, "SVBTDF_INJECT_FAULT=" + std::to_string(n) + ":" + action);
    if (faulted.exit_code == 0) {  // fewer operations than n: an undisturbed run
      EXPECT_TRUE(Images(out / "session") == *reference_images_) << "operation " << n;
      fs::remove_all(out);
      return false;
    }
    if (action == "enospc") {
      EXPECT_EQ(faulted.exit_code, 1) << "operation " << n << ": " << faulted.output;
      EXPECT_NE(faulted.output.find("No space left on device"), std::string::npos) << n << ": " << faulted.output;
      EXPECT_NE(faulted.output.find(out.string()), std::string::npos) << "the message names the file: " << faulted.output;
    }
    const auto resumed = RunSvbtdf(simulate);
    EXPECT_EQ(resumed.exit_code, 0) << "operation " << n << " (" << action << "): " << resumed.output;
    const auto verify = RunSvbtdf("session verify --decode " + (out / "session").string());
    EXPECT_EQ(verify.exit_code, 0) << "operation " << n << ": " << verify.output;
    EXPECT_TRUE(Images(out / "session") == *reference_images_) << "operation " << n << " (" << action << ")";
    EXPECT_EQ(TemporaryFilesUnder(out), 0) << "operation " << n;
    fs::remove_all(out);
    return true;
  }

  testing::TempFolder folder_;
  static testing::TempFolder* reference_;
  static std::map<std::string, std::string>* reference_images_;
};

testing::TempFolder* Durability::reference_ = nullptr;
std::map<std::string, std::string>* Durability::reference_images_ = nullptr;

// Which durable operations of `simulate --preset tiny` to fail. The first ones create the truth
// and the session; then each capture is six (the image's write, fsync, rename and folder fsync,
// the journal line's write and fsync), so six in a row meet every step of a capture. Each point
// costs about one whole simulation (the faulted run and its resume), so the default run takes a
// sample; SVBTDF_WALK_EVERY_OPERATION=K walks every K-th operation to the end (K = 1: all of them).
std::vector<int64_t> OperationsToWalk() {
  std::vector<int64_t> walk;
  if (const char* every = std::getenv("SVBTDF_WALK_EVERY_OPERATION")) {
    const int64_t stride = std::max<int64_t>(1, std::atoll(every));
    for (int64_t n = 1; n <= 100000; n += stride) walk.push_back(n);
    return walk;
  }
  for (int64_t n = 1; n <= 8; ++n) walk.push_back(n);
  for (int64_t n = 200; n < 206; ++n) walk.push_back(n);
  walk.push_back(100000);  // beyond the end: the run must not be disturbed
  return walk;
}

TEST_F(Durability, AFullDiskAtAnyWriteResumesToTheSameSession) {
  int injected = 0;
  for (const int64_t n : OperationsToWalk()) {
    if (!FaultThenResume(n, "enospc")) break;
    ++injected;
  }
  EXPECT_GE(injected, 14) << "the walk must reach the captures";
  std::printf("full disk injected at %d durable operations of `simulate --preset tiny`\n", injected);
}

TEST_F(Durability, AKillAtAnyWriteResumesToTheSameSession) {
  int injected = 0;
  for (const int64_t n : OperationsToWalk()) {
    if (!FaultThenResume(n, "kill")) break;
    ++injected;
  }
  EXPECT_GE(injected, 14) << "the walk must reach the captures";
  std::printf("SIGKILL injected at %d durable operations of `simulate --preset tiny`\n", injected);
}

// A second writer of one folder is refused, naming the holder, and changes nothing.
TEST_F(Durability, ASecondWriterOfAFolderIsRefused) {
  const fs::path out = folder_.path() / "busy";
  const common::FolderLock held = common::FolderLock::Acquire(out, "a test");
  for (const std::string& command : {"-q simulate --preset tiny --out " + out.string(),
                                     "acquire --plan-preset tiny --camera sim:" + (reference_->path() / "tiny").string() +
                                         " --display sim --out " + out.string(),
                                     "fit " + out.string() + ".store --out " + out.string()}) {
    const auto refused = RunSvbtdf(command);
    EXPECT_EQ(refused.exit_code, 1) << command << ": " << refused.output;
    EXPECT_NE(refused.output.find("is being written by PID " + std::to_string(::getpid()) + " (a test)"),
              std::string::npos)
        << command << ": " << refused.output;
    EXPECT_FALSE(fs::exists(out)) << command;
  }
}

int JournalLines(const fs::path& session_folder) {
  std::error_code error;
  if (!fs::exists(session_folder / "journal.jsonl", error)) return 0;
  const std::string text = common::ReadTextFile(session_folder / "journal.jsonl");
  return static_cast<int>(std::count(text.begin(), text.end(), '\n'));
}

// A real full disk (a tmpfs, which needs root, as CI has): the free-space check lets the capture
// start, then the disk fills under it (a ballast file written once ten images are journalled).
// The run stops with one line naming the file, nothing broken is journalled, and once space is
// freed the resumed run completes with the uninterrupted run's images.
TEST_F(Durability, ARealFullDiskStopsCleanlyAndResumes) {
  const fs::path mount_point = folder_.path() / "small-disk";
  fs::create_directories(mount_point);
  if (::geteuid() != 0 || ::mount("tmpfs", mount_point.c_str(), "tmpfs", 0, "size=160m") != 0) {
    GTEST_SKIP() << "cannot mount a tmpfs here (not root?)";
  }
  const fs::path out = mount_point / "tiny";
  const std::string simulate = "-q simulate --preset tiny --out " + out.string();
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    const int null = ::open("/dev/null", O_WRONLY);
    ::dup2(null, 1);
    ::execl(SVBTDF_CLI_PATH, SVBTDF_CLI_PATH, "-q", "simulate", "--preset", "tiny", "--out", out.c_str(), nullptr);
    ::_exit(127);
  }
  while (JournalLines(out / "session") < 10 && ::waitpid(child, nullptr, WNOHANG) == 0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  {  // fill the disk: write until the kernel refuses
    std::ofstream ballast(mount_point / "ballast", std::ios::binary);
    const std::string block(1 << 20, 'b');
    while (ballast.write(block.data(), block.size())) {}
  }
  int status = 0;
  ::waitpid(child, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 1) << "the full disk must stop the run";
  const auto verify = RunSvbtdf("session verify --decode " + (out / "session").string());
  EXPECT_EQ(verify.output.find("corrupt"), std::string::npos) << "a broken image was journalled: " << verify.output;
  const auto full = RunSvbtdf(simulate);  // resuming while the disk is still full: a clear refusal
  EXPECT_EQ(full.exit_code, 1) << full.output;
  EXPECT_NE(full.output.find(out.string()), std::string::npos) << full.output;
  fs::remove(mount_point / "ballast");
  const auto resumed = RunSvbtdf(simulate);
  EXPECT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_EQ(RunSvbtdf("session verify --decode " + (out / "session").string()).exit_code, 0);
  EXPECT_TRUE(Images(out / "session") == *reference_images_);
  EXPECT_EQ(TemporaryFilesUnder(out), 0);
  ::umount2(mount_point.c_str(), MNT_DETACH);
}

}  // namespace
}  // namespace svbtdf
