// Atomic writes (common/src/atomic_file.cc): a file is replaced whole or not at all, and no
// temporary is left behind.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/fault_injection.h"
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

size_t FilesIn(const fs::path& dir) {
  return static_cast<size_t>(std::distance(fs::recursive_directory_iterator(dir), fs::recursive_directory_iterator()));
}

// /dev/full answers every write with ENOSPC, as a full disk does: the checked write must say so.
TEST(AtomicFile, AFullDeviceIsAnErrorNamingTheFileAndTheDiskFull) {
  const int fd = ::open("/dev/full", O_WRONLY | O_CLOEXEC);
  if (fd < 0) GTEST_SKIP() << "no /dev/full here";
  const std::string bytes(100000, 'x');
  try {
    WriteAllOrThrow(fd, bytes.data(), bytes.size(), "images/dot.png");
    ADD_FAILURE() << "a write to /dev/full succeeded";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kIo);
    EXPECT_NE(std::string(e.what()).find("images/dot.png"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("No space left on device"), std::string::npos) << e.what();
    EXPECT_NE(e.hint().find("disk is full"), std::string::npos) << e.what();
  }
  ::close(fd);
}

// The steps of an atomic write are the write, the file's fsync, the rename and the folder's
// fsync. A failure before the rename leaves the old file and nothing else; a failure of the last
// fsync is still reported (the new file's name may not be durable yet).
TEST(AtomicFile, AFailureAtAnyStepLeavesTheOldFileAndNoTemporary) {
  const testing::TempFolder folder;
  const fs::path file = folder.path() / "state.json";
  WriteTextAtomically(file, "old");
  for (int step = 1; step <= 3; ++step) {
    InjectFaultForTesting(step, FaultAction::kFail);
    EXPECT_THROW(WriteTextAtomically(file, "new"), Error) << "step " << step;
    InjectFaultForTesting(0, FaultAction::kProceed);
    EXPECT_EQ(ReadTextFile(file), "old") << "step " << step;
    EXPECT_EQ(FilesIn(folder.path()), 1u) << "step " << step;
  }
  InjectFaultForTesting(4, FaultAction::kFail);
  EXPECT_THROW(WriteTextAtomically(file, "new"), Error);
  EXPECT_EQ(FilesIn(folder.path()), 1u);
  InjectFaultForTesting(5, FaultAction::kFail);  // falls after this write: nothing fails
  WriteTextAtomically(file, "newer");
  InjectFaultForTesting(0, FaultAction::kProceed);
  EXPECT_EQ(ReadTextFile(file), "newer");
}

TEST(AtomicFile, AWriterThatWritesNothingHasFailed) {
  const testing::TempFolder folder;
  const fs::path file = folder.path() / "image.png";
  EXPECT_THROW(WriteFileAtomically(file, [](const fs::path& temp) { std::ofstream touch(temp); }), Error);
  EXPECT_FALSE(fs::exists(file));
  EXPECT_EQ(FilesIn(folder.path()), 0u);
}

TEST(AtomicFile, AFolderIsCreatedWholeOrNotAtAll) {
  const testing::TempFolder folder;
  const fs::path target = folder.path() / "session";
  EXPECT_THROW(CreateFolderAtomically(target,
                                      [](const fs::path& staging) {
                                        WriteTextAtomically(staging / "plan.json", "{}");
                                        throw Error(ErrorKind::kIo, "session.json", "cannot write");
                                      }),
               Error);
  EXPECT_FALSE(fs::exists(target));
  EXPECT_EQ(FilesIn(folder.path()), 0u);
  // What a kill mid-creation leaves (a hidden staging folder) is removed by the next creation.
  fs::create_directories(folder.path() / ".session.tmp-dead" / "images");
  CreateFolderAtomically(target, [](const fs::path& staging) { WriteTextAtomically(staging / "plan.json", "{}"); });
  EXPECT_EQ(ReadTextFile(target / "plan.json"), "{}");
  EXPECT_EQ(FilesIn(folder.path()), 2u);  // session/ and session/plan.json
  // An existing, non-empty folder is never replaced.
  EXPECT_THROW(CreateFolderAtomically(target, [](const fs::path&) {}), Error);
  EXPECT_EQ(ReadTextFile(target / "plan.json"), "{}");
}

TEST(AtomicFile, StaleTemporaryFilesAreRemovedAndCounted) {
  const testing::TempFolder folder;
  fs::create_directories(folder.path() / "images" / "dot");
  WriteTextAtomically(folder.path() / "images" / "dot" / "q0.png", "image");
  std::ofstream(folder.path() / "images" / "dot" / ".q1.png.tmp-1f2e") << "half";
  std::ofstream(folder.path() / ".session.json.tmp-77") << "half";
  std::ofstream(folder.path() / ".hidden-but-mine") << "keep";
  EXPECT_EQ(RemoveStaleTemporaryFiles(folder.path()), 2);
  EXPECT_TRUE(fs::exists(folder.path() / "images" / "dot" / "q0.png"));
  EXPECT_TRUE(fs::exists(folder.path() / ".hidden-but-mine"));
  EXPECT_EQ(RemoveStaleTemporaryFiles(folder.path()), 0);
}

}  // namespace
}  // namespace svbtdf::common
