// Atomic writes (common/src/atomic_file.cc): a file is replaced whole or not at all, and no
// temporary is left behind.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "temp_folder.h"

namespace svbtdf::common {
namespace {

namespace fs = std::filesystem;

TEST(AtomicFile, ReplacesContentsAndLeavesNoTemporaryFiles) {
  const testing::TempFolder folder;
  const fs::path& dir = folder.path();
  const fs::path file = dir / "a.json";
  WriteTextAtomically(file, "first");
  WriteTextAtomically(file, "second");
  EXPECT_EQ(ReadTextFile(file), "second");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
}

TEST(AtomicFile, RefusesToOverwriteWhenAskedAndKeepsTheOriginal) {
  const testing::TempFolder folder;
  const fs::path& dir = folder.path();
  const fs::path file = dir / "capture.exr";
  WriteTextAtomically(file, "precious");
  EXPECT_THROW(WriteTextAtomically(file, "other", /*overwrite=*/false), Error);
  EXPECT_EQ(ReadTextFile(file), "precious");
}

TEST(AtomicFile, AFailedWriterLeavesTheOldFileAndNoTemporary) {
  const testing::TempFolder folder;
  const fs::path& dir = folder.path();
  const fs::path file = dir / "state.json";
  WriteTextAtomically(file, "old");
  EXPECT_THROW(WriteFileAtomically(file, [](const fs::path&) { throw std::runtime_error("boom"); }),
               std::runtime_error);
  EXPECT_EQ(ReadTextFile(file), "old");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
}

TEST(AtomicFile, MissingFileErrorNamesTheFile) {
  try {
    ReadTextFile("/nonexistent/svbtdf/file.json");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kIo);
    EXPECT_NE(std::string(e.what()).find("/nonexistent/svbtdf/file.json"), std::string::npos);
  }
}

TEST(AtomicFile, TrailingSeparatorsNameTheSameFolder) {
  EXPECT_EQ(WithoutTrailingSeparators("mat/"), fs::path("mat"));
  EXPECT_EQ(WithoutTrailingSeparators("a/mat///"), fs::path("a/mat"));
  EXPECT_EQ(WithoutTrailingSeparators("a/mat"), fs::path("a/mat"));
  EXPECT_EQ(WithoutTrailingSeparators("/"), fs::path("/"));
  EXPECT_EQ(WithoutTrailingSeparators(""), fs::path(""));
}

}  // namespace
}  // namespace svbtdf::common
