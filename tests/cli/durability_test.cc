// What the commands promise about a user's data (docs/capture.md, "Durability"): a full disk or
// a kill at any write is resumed to the same images as an uninterrupted run, a failed write is
// never journalled, and two commands never write one folder at once.
#include <gtest/gtest.h>
#include <sys/mount.h>
#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <functional>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <thread>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "run_command.h"
#include "shared_test_data.h"
#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/folder_lock.h"
#include "svbtdf/common/image_io.h"
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

// Pixels of every image map in `folder` and the bytes of its other files (EXR headers carry the
// time they were written, so maps are compared by their values).
std::map<std::string, std::string> Contents(const fs::path& folder) {
  std::map<std::string, std::string> contents;
  for (const auto& entry : fs::directory_iterator(folder)) {
    const std::string name = entry.path().filename().string();
    if (name == "progress.jsonl" || name == "material.json" || name == "quality.json") continue;  // paths, times
    if (entry.path().extension() == ".exr") {
      const common::FloatImage image = common::ReadFloatImage(entry.path());
      contents[name] = std::string(reinterpret_cast<const char*>(image.pixels.data()), image.pixels.size() * sizeof(float));
    } else {
      contents[name] = common::ReadTextFile(entry.path());
    }
  }
  return contents;
}

class Durability : public ::testing::Test {
 protected:
  // The uninterrupted runs, made once for all of the program's tests (ctest runs each in a
  // process of its own): tiny simulated, calibrated, processed and fitted.
  static void SetUpTestSuite() {
    const std::string recipe = "simulate, calibrate, process, fit tiny";
    reference_ = testing::SharedTestData("durability", recipe, [](const fs::path& shared) {
      const fs::path tiny = shared / "tiny", store = shared / "store";
      ASSERT_EQ(RunSvbtdf("-q simulate --preset tiny --out " + tiny.string()).exit_code, 0);
      ASSERT_EQ(RunSvbtdf("-q calibrate " + (tiny / "session").string()).exit_code, 0);
      ASSERT_EQ(RunSvbtdf("-q process " + (tiny / "session").string() + " --out " + store.string()).exit_code, 0);
      ASSERT_EQ(RunSvbtdf("-q fit " + store.string() + " --out " + (shared / "material").string()).exit_code, 0);
    });
    reference_images_ = new std::map<std::string, std::string>(Images(Session()));
  }
  static void TearDownTestSuite() { delete reference_images_; }
  static fs::path Session() { return reference_ / "tiny" / "session"; }
  static fs::path Store() { return reference_ / "store"; }
  static fs::path Material() { return reference_ / "material"; }

  // Runs `svbtdf ARGUMENTS --out OUT` with the n-th durable operation failing as `action` says
  // (enospc or kill), then again without faults. Returns false when the run had fewer than n
  // durable operations (nothing was injected); then the run itself must have succeeded.
  bool FaultThenResume(const std::string& arguments, const fs::path& out, int64_t n, const std::string& action) {
    const std::string command = "-q " + arguments + " --out " + out.string();
    const auto faulted = RunSvbtdf(command, "SVBTDF_INJECT_FAULT=" + std::to_string(n) + ":" + action);
    if (faulted.exit_code == 0) return false;
    if (action == "enospc") {
      EXPECT_EQ(faulted.exit_code, 1) << arguments << ", operation " << n << ": " << faulted.output;
      EXPECT_NE(faulted.output.find("No space left on device"), std::string::npos) << n << ": " << faulted.output;
      EXPECT_NE(faulted.output.find(out.string()), std::string::npos) << "the message names the file: " << faulted.output;
    }
    const auto resumed = RunSvbtdf(command);
    EXPECT_EQ(resumed.exit_code, 0) << arguments << ", operation " << n << " (" << action << "): " << resumed.output;
    return true;
  }

  // Walks `points` (alternating a full disk and a kill) over `arguments`; `check(out, n)` judges
  // each resumed result. Returns how many points were injected.
  int Walk(const std::string& arguments, const std::vector<int64_t>& points,
           const std::function<void(const fs::path&, int64_t)>& check) {
    int injected = 0;
    for (size_t k = 0; k < points.size(); ++k) {
      const fs::path out = folder_.path() / ("out" + std::to_string(points[k]));
      const bool fault = FaultThenResume(arguments, out, points[k], k % 2 == 0 ? "enospc" : "kill");
      check(out, points[k]);
      EXPECT_EQ(TemporaryFilesUnder(out.parent_path()), 0) << "operation " << points[k];
      fs::remove_all(out);
      fs::remove(out.string() + ".partial-fits.jsonl");
      if (!fault) break;
      ++injected;
    }
    return injected;
  }

  testing::TempFolder folder_;
  static inline fs::path reference_;  // shared by the program's processes: read, never written
  static std::map<std::string, std::string>* reference_images_;
};

std::map<std::string, std::string>* Durability::reference_images_ = nullptr;

// Every K-th operation to the end when SVBTDF_WALK_EVERY_OPERATION=K is set (K = 1: all; the
// slow test durability.every_operation), but not the operations in `excluded`.
std::vector<int64_t> PointsOrEvery(std::vector<int64_t> points, const std::vector<int64_t>& excluded = {}) {
  if (const char* every = std::getenv("SVBTDF_WALK_EVERY_OPERATION")) {
    points.clear();
    const int64_t stride = std::max<int64_t>(1, std::atoll(every));
    for (int64_t n = 1; n <= 100000; n += stride) {
      if (std::find(excluded.begin(), excluded.end(), n) == excluded.end()) points.push_back(n);
    }
  }
  points.push_back(100000);  // beyond the end: an undisturbed run
  return points;
}

// `simulate --preset tiny` makes about 591 durable operations: the truth's six files and rig.json
// (four each: write, fsync, rename, folder fsync), the session's creation (plan.json and
// session.json in a staging folder, its fsync and rename), then six per capture (the image's
// four, the journal line's write and fsync). The points meet each of those; six in a row meet
// every step of one capture. Each costs about one whole simulation.
TEST_F(Durability, AFullDiskOrAKillAtAnyWriteOfSimulateResumesToTheSameSession) {
  const int injected = Walk("simulate --preset tiny", PointsOrEvery({1, 4, 24, 27, 31, 38, 200, 201, 202, 203, 204, 205, 591}),
                            [&](const fs::path& out, int64_t n) {
                              const auto verify = RunSvbtdf("session verify --decode " + (out / "session").string());
                              EXPECT_EQ(verify.exit_code, 0) << "operation " << n << ": " << verify.output;
                              EXPECT_TRUE(Images(out / "session") == *reference_images_) << "operation " << n;
                            });
  EXPECT_GE(injected, 13);
  std::printf("simulate: a full disk or a kill at %d durable operations, each resumed to the same session\n", injected);
}

// `process` (69 operations on tiny: 1-8 the store made in a staging folder, 9-48 the dots'
// tiles written, 49-51 their group commit (the samples' fsync, the journal's lines written and
// fsync'ed), 52-53 the slices, then the maps and the manifest) and `fit` (about 95: the checkpoint's lines, the material built
// in a staging folder, 28 of them its seven standard-error maps) resume from any fault to the uninterrupted run's values. A fault beyond the
// last operation (PointsOrEvery's last point) must leave the run undisturbed.
TEST_F(Durability, AFullDiskOrAKillAtAnyWriteOfProcessOrFitResumesToTheSameResult) {
  const std::map<std::string, std::string> store = Contents(Store());
  const int processed = Walk("process " + Session().string(),
                             PointsOrEvery({1, 2, 3, 4, 5, 6, 9, 20, 35, 48, 49, 50, 51, 52, 60, 69}),
                             [&](const fs::path& out, int64_t n) {
                               EXPECT_TRUE(Contents(out) == store) << "process, operation " << n;
                             });
  const std::map<std::string, std::string> material = Contents(Material());
  // Not 95, the fsync of the material's parent folder after the rename: a kill there leaves the
  // whole material in place, which a rerun refuses to overwrite (exit 2), as it must (the test
  // AKillAfterTheMaterialIsInPlace... covers it).
  const int fitted = Walk("fit " + Store().string(), PointsOrEvery({1, 2, 3, 4, 5, 6, 15, 29, 43, 57, 71, 85, 92, 94}, {95}),
                          [&](const fs::path& out, int64_t n) {
                            EXPECT_TRUE(Contents(out) == material) << "fit, operation " << n;
                          });
  EXPECT_GE(processed, 15);
  EXPECT_GE(fitted, 12);
  std::printf("process: %d faults, fit: %d faults, each resumed to the same result\n", processed, fitted);
}

// A kill after the material is renamed into place (fit's last durable operation, the parent
// folder's fsync) leaves the whole material and its checkpoint: a rerun refuses to overwrite the
// material and removes the checkpoint, which no longer serves anything.
TEST_F(Durability, AKillAfterTheMaterialIsInPlaceLeavesItWholeAndItsCheckpointIsRemoved) {
  const fs::path out = folder_.path() / "material";
  const std::string fit = "-q fit " + Store().string() + " --out " + out.string();
  EXPECT_NE(RunSvbtdf(fit, "SVBTDF_INJECT_FAULT=95:kill").exit_code, 0);
  const fs::path checkpoint = out.string() + ".partial-fits.jsonl";
  ASSERT_TRUE(fs::exists(checkpoint)) << "operation 95 is no longer the last: update the walk's points";
  EXPECT_TRUE(Contents(out) == Contents(Material()));
  const auto rerun = RunSvbtdf(fit);
  EXPECT_EQ(rerun.exit_code, 2) << rerun.output;
  EXPECT_NE(rerun.output.find("never overwritten"), std::string::npos) << rerun.output;
  EXPECT_FALSE(fs::exists(checkpoint));
}

// A second writer of one folder is refused, naming the holder, and changes nothing.
TEST_F(Durability, ASecondWriterOfAFolderIsRefused) {
  const fs::path out = folder_.path() / "busy";
  const common::FolderLock held = common::FolderLock::Acquire(out, "a test");
  for (const std::string& command : {"-q simulate --preset tiny --out " + out.string(),
                                     "acquire --plan-preset tiny --camera sim:" + (reference_ / "tiny").string() +
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
