#pragma once
// Test data made once and shared, read-only, by every process of a test program.
//
// Why: ctest runs each test of a program in a process of its own (gtest_discover_tests), so a
// fixture's SetUpTestSuite runs once per test, not once per program: the `small` session of
// FitChain was simulated and processed three times in every default run. SharedTestData makes
// a recipe's folder once per build, beside the test program, and hands the same folder to every
// later process. It is made again when the recipe changes or when a program that makes it (the
// test program itself, the command line) is rebuilt. A file lock makes a second process that
// asks while the first is making it wait and then reuse it. The folder is made where it stays (its
// files may name their paths) and marked finished last, so that a failed or killed making leaves
// nothing that looks finished.
//
// The folder is shared: a test must write its own outputs elsewhere (a TempFolder).

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <unistd.h>

#include <filesystem>
#include <functional>
#include <sstream>
#include <string>

#include "svbtdf/common/atomic_file.h"

namespace svbtdf::testing {

namespace shared_test_data_detail {

namespace fs = std::filesystem;

// What makes the data, as text: the recipe and the size and time of every program that makes it.
inline std::string Key(const std::string& recipe, const fs::path& self) {
  std::ostringstream key;
  key << recipe << "\n";
  for (const fs::path& program : {self, fs::path(SVBTDF_CLI_PATH)}) {
    std::error_code missing;  // the checked build has no command line
    const auto size = fs::file_size(program, missing);
    if (missing) continue;
    key << program.string() << " " << size << " " << fs::last_write_time(program).time_since_epoch().count() << "\n";
  }
  return key.str();
}

// Holds an exclusive flock on `file` for its lifetime.
class ExclusiveLock {
 public:
  explicit ExclusiveLock(const fs::path& file) : fd_(::open(file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644)) {
    if (fd_ < 0 || ::flock(fd_, LOCK_EX) != 0) ADD_FAILURE() << "cannot lock " << file;
  }
  ~ExclusiveLock() {
    if (fd_ >= 0) ::close(fd_);  // closing releases the lock
  }
  ExclusiveLock(const ExclusiveLock&) = delete;
  ExclusiveLock& operator=(const ExclusiveLock&) = delete;

 private:
  int fd_;
};

}  // namespace shared_test_data_detail

// The folder `name` made by `make(folder)` for `recipe` (a description of everything `make` does
// that is not in the programs' code: commands, options, environment). `make` reports failures
// with gtest's assertions; a failed making is not published, and the next process tries again.
inline std::filesystem::path SharedTestData(const std::string& name, const std::string& recipe,
                                            const std::function<void(const std::filesystem::path&)>& make) {
  namespace fs = std::filesystem;
  using namespace shared_test_data_detail;
  const fs::path self = fs::canonical("/proc/self/exe");
  const fs::path root = self.parent_path() / "shared-test-data" / self.filename();
  const fs::path folder = root / name;
  fs::create_directories(root);
  const ExclusiveLock lock(root / (name + ".lock"));
  const std::string key = Key(recipe, self);
  const fs::path finished = folder / "recipe.txt";
  if (fs::exists(finished) && common::ReadTextFile(finished) == key) return folder;

  fs::remove_all(folder);
  fs::create_directories(folder);
  make(folder);
  if (::testing::Test::HasFailure()) return folder;  // unpublished: the next process makes it again
  common::WriteTextAtomically(finished, key);        // written last: the folder is finished
  return folder;
}

}  // namespace svbtdf::testing
