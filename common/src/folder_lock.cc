#include "svbtdf/common/folder_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <string>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/fault_injection.h"

namespace svbtdf::common {
namespace fs = std::filesystem;
namespace {

std::string ReadHolder(int fd) {
  char buffer[256] = {};
  const ssize_t n = ::pread(fd, buffer, sizeof buffer - 1, 0);
  std::string text(buffer, n > 0 ? static_cast<size_t>(n) : 0);
  while (!text.empty() && (text.back() == '\n' || text.back() == '\0')) text.pop_back();
  return text.empty() ? "another process" : text;
}

// After flock succeeds the path may name a newer file: the previous holder unlinked the one we
// locked as it finished. Then our lock protects nothing and we must try again.
bool StillNamesLockedFile(int fd, const fs::path& path) {
  struct stat held {}, named {};
  return ::fstat(fd, &held) == 0 && ::stat(path.c_str(), &named) == 0 && held.st_ino == named.st_ino &&
         held.st_dev == named.st_dev;
}

}  // namespace

fs::path LockFileFor(const fs::path& folder) {
  const fs::path clean = fs::absolute(WithoutTrailingSeparators(folder)).lexically_normal();
  const fs::path name = WithoutTrailingSeparators(clean).filename();
  return clean.parent_path() / ("." + name.string() + ".lock");
}

FolderLock FolderLock::Acquire(const fs::path& folder, const std::string& command) {
  const fs::path lock_file = LockFileFor(folder);
  // The command would create the folder's parents anyway; the lock needs them first.
  std::error_code error;
  fs::create_directories(lock_file.parent_path(), error);
  if (error) ThrowSystemError(folder.string(), "cannot create its parent folder " + lock_file.parent_path().string(), error.value());
  for (int attempt = 0; attempt < 100; ++attempt) {
    const int fd = ::open(lock_file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0) ThrowSystemError(lock_file.string(), "cannot create the folder's lock file", errno);
    if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
      const int error = errno;
      const std::string holder = ReadHolder(fd);
      ::close(fd);
      if (error != EWOULDBLOCK) ThrowSystemError(lock_file.string(), "cannot lock", error);
      ThrowIoError(folder.string(), "is being written by " + holder,
                   "wait for it to finish or stop it; two commands never write one folder at once");
    }
    if (!StillNamesLockedFile(fd, lock_file)) {
      ::close(fd);
      continue;
    }
    const std::string holder = "PID " + std::to_string(::getpid()) + " (" + command + ")\n";
    if (::ftruncate(fd, 0) != 0 || ::pwrite(fd, holder.data(), holder.size(), 0) < 0) {
      const int error = errno;
      ::close(fd);
      ThrowSystemError(lock_file.string(), "cannot write the folder's lock file", error);
    }
    return FolderLock(lock_file, fd);
  }
  ThrowIoError(lock_file.string(), "keeps being replaced by other processes; cannot lock the folder");
}

FolderLock::FolderLock(FolderLock&& other) noexcept : lock_file_(std::move(other.lock_file_)), fd_(other.fd_) {
  other.fd_ = -1;
}

FolderLock::~FolderLock() {
  if (fd_ < 0) return;
  // Unlink while still holding the lock: a waiter that opened this file finds it unlinked and
  // retries on a fresh one (StillNamesLockedFile).
  ::unlink(lock_file_.c_str());
  ::close(fd_);
}

}  // namespace svbtdf::common
