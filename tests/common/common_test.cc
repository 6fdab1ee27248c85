// Tests of the common vocabulary: errors, atomic writes.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"

namespace svbtdf {
namespace {

namespace fs = std::filesystem;

fs::path FreshTempDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("svbtdf-test-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

TEST(Error, MessageNamesSubjectProblemAndHint) {
  const Error error(ErrorKind::kInvalidInput, "--eta", "must be greater than 1", "got 0.9");
  EXPECT_STREQ(error.what(), "--eta: must be greater than 1 (got 0.9)");
  EXPECT_EQ(ExitCodeFor(error.kind()), 2);
  EXPECT_EQ(ExitCodeFor(ErrorKind::kIo), 1);
  EXPECT_EQ(ExitCodeFor(ErrorKind::kInterrupted), 130);
}

TEST(AtomicFile, ReplacesContentsAndLeavesNoTemporaryFiles) {
  const fs::path dir = FreshTempDir("atomic");
  const fs::path file = dir / "a.json";
  WriteTextAtomically(file, "first");
  WriteTextAtomically(file, "second");
  EXPECT_EQ(ReadTextFile(file), "second");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
  fs::remove_all(dir);
}

TEST(AtomicFile, RefusesToOverwriteWhenAskedAndKeepsTheOriginal) {
  const fs::path dir = FreshTempDir("atomic-keep");
  const fs::path file = dir / "capture.exr";
  WriteTextAtomically(file, "precious");
  EXPECT_THROW(WriteTextAtomically(file, "other", /*overwrite=*/false), Error);
  EXPECT_EQ(ReadTextFile(file), "precious");
  fs::remove_all(dir);
}

TEST(AtomicFile, AFailedWriterLeavesTheOldFileAndNoTemporary) {
  const fs::path dir = FreshTempDir("atomic-fail");
  const fs::path file = dir / "state.json";
  WriteTextAtomically(file, "old");
  EXPECT_THROW(WriteFileAtomically(file, [](const fs::path&) { throw std::runtime_error("boom"); }),
               std::runtime_error);
  EXPECT_EQ(ReadTextFile(file), "old");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
  fs::remove_all(dir);
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

}  // namespace
}  // namespace svbtdf
