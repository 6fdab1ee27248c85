// simulate::ReadTruth: a folder of neither truth kind is named. (Both kinds are read and scored
// in tests/report/compare_test.cc, which simulates them.)
#include "svbtdf/simulate/truth.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"

namespace svbtdf::simulate {
namespace {
namespace fs = std::filesystem;

TEST(ReadTruth, AFolderOfNeitherKindNamesItsManifest) {
  const fs::path folder = fs::temp_directory_path() / ("svbtdf-bad-truth-" + std::to_string(::getpid()));
  fs::remove_all(folder);
  fs::create_directories(folder);
  common::WriteTextAtomically(folder / "material.json", "{}");
  try {
    ReadTruth(folder);
    FAIL() << "a truth of no kind was read";
  } catch (const common::Error& e) {
    EXPECT_NE(std::string(e.what()).find("material.json"), std::string::npos) << e.what();
  }
  fs::remove_all(folder);
}

}  // namespace
}  // namespace svbtdf::simulate
