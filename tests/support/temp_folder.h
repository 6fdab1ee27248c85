#pragma once
// The one temporary-folder helper of the tests: a fresh, empty folder named after the running
// test and the process (ctest runs test programs side by side), removed when it goes out of
// scope unless SVBTDF_KEEP_TEST_FILES is set (to look at what a failing test wrote).

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>

namespace svbtdf::testing {

class TempFolder {
 public:
  // `tag` tells apart several folders of one test.
  explicit TempFolder(const std::string& tag = "") : path_(UniquePath(tag)) {
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempFolder() {
    if (std::getenv("SVBTDF_KEEP_TEST_FILES") == nullptr) {
      std::error_code ignored;
      std::filesystem::remove_all(path_, ignored);
    }
  }
  TempFolder(const TempFolder&) = delete;
  TempFolder& operator=(const TempFolder&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::filesystem::path& relative) const { return path_ / relative; }

 private:
  static std::filesystem::path UniquePath(const std::string& tag) {
    std::string name = "svbtdf";
    if (const ::testing::TestInfo* test = ::testing::UnitTest::GetInstance()->current_test_info()) {
      name.append("-").append(test->test_suite_name()).append("-").append(test->name());
    }
    // append, not "-" + s: GCC 12 warns falsely (-Wrestrict) on the latter.
    if (!tag.empty()) name.append("-").append(tag);
    name.append("-").append(std::to_string(::getpid()));
    for (char& c : name) {
      if (c == '/') c = '_';  // parameterised test names hold slashes
    }
    return std::filesystem::temp_directory_path() / name;
  }

  std::filesystem::path path_;
};

}  // namespace svbtdf::testing
