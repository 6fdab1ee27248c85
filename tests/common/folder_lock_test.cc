// One writer per output folder (common/src/folder_lock.cc): a second writer is refused with the
// holder's PID, and a holder's death, however it dies, frees the folder.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <optional>
#include <string>

#include "svbtdf/common/error.h"
#include "svbtdf/common/folder_lock.h"
#include "temp_folder.h"

namespace svbtdf::common {
namespace {
namespace fs = std::filesystem;

std::string RefusalOf(const fs::path& folder) {
  try {
    FolderLock::Acquire(folder, "svbtdf second");
  } catch (const Error& e) {
    return e.what();
  }
  return {};
}

TEST(FolderLock, ASecondWriterIsRefusedNamingTheHolder) {
  const testing::TempFolder root;
  const fs::path out = root / "session";
  {
    const FolderLock lock = FolderLock::Acquire(out, "svbtdf acquire");
    EXPECT_FALSE(fs::exists(out)) << "the lock is taken before the folder exists";
    const std::string refusal = RefusalOf(out / "");  // a trailing slash names the same folder
    EXPECT_NE(refusal.find(out.string()), std::string::npos) << refusal;
    EXPECT_NE(refusal.find("PID " + std::to_string(::getpid()) + " (svbtdf acquire)"), std::string::npos) << refusal;
  }
  EXPECT_FALSE(fs::exists(LockFileFor(out))) << "a holder that ends normally removes its lock file";
  EXPECT_EQ(RefusalOf(out), "");
}

TEST(FolderLock, AKilledHolderFreesTheFolder) {
  const testing::TempFolder root;
  const fs::path out = root / "material";
  int ready[2];
  ASSERT_EQ(::pipe(ready), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    const FolderLock lock = FolderLock::Acquire(out, "svbtdf fit");
    const char byte = 1;
    if (::write(ready[1], &byte, 1) != 1) ::_exit(1);
    ::pause();
    ::_exit(0);
  }
  char byte = 0;
  ASSERT_EQ(::read(ready[0], &byte, 1), 1);
  const std::string refusal = RefusalOf(out);
  EXPECT_NE(refusal.find("PID " + std::to_string(child) + " (svbtdf fit)"), std::string::npos) << refusal;
  ::kill(child, SIGKILL);
  int status = 0;
  ::waitpid(child, &status, 0);
  EXPECT_TRUE(fs::exists(LockFileFor(out))) << "a killed holder cannot clean up";
  EXPECT_EQ(RefusalOf(out), "") << "the kernel released the dead holder's lock";
  ::close(ready[0]);
  ::close(ready[1]);
}

TEST(FolderLock, MissingParentsAreCreatedAndImpossibleOnesNamed) {
  const testing::TempFolder root;
  { const FolderLock lock = FolderLock::Acquire(root / "a" / "b" / "store", "svbtdf process"); }
  EXPECT_TRUE(fs::is_directory(root / "a" / "b"));
  std::ofstream(root / "file") << "not a folder";
  const std::string refusal = RefusalOf(root / "file" / "out");
  EXPECT_NE(refusal.find((root / "file" / "out").string()), std::string::npos) << refusal;
  EXPECT_NE(refusal.find("cannot create its parent folder"), std::string::npos) << refusal;
}

}  // namespace
}  // namespace svbtdf::common
