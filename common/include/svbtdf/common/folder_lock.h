#pragma once
// One writer per output folder. Two commands writing one folder (two `acquire` runs on one
// --out, a `fit` started twice) would interleave their journals and, on a rig, drive one display
// from two processes. Every command that writes a folder holds this lock while it does.
//
// The lock is flock(2) on a hidden sibling, PARENT/.NAME.lock, so that it can be taken before the
// folder exists (and while the folder is being created under a temporary name and renamed into
// place). The file records the holder's PID and command for the refusal message. The kernel
// drops the lock when its holder dies, however it dies, so a lock file left by a kill never blocks
// anyone; a holder that ends normally removes it.

#include <filesystem>
#include <string>

namespace svbtdf::common {

class FolderLock {
 public:
  // Takes the lock on `folder` for `command` (e.g. "svbtdf acquire"), without waiting: when another
  // process holds it, throws Error(kIo) naming the folder and the holder's PID and command.
  static FolderLock Acquire(const std::filesystem::path& folder, const std::string& command);

  FolderLock(FolderLock&& other) noexcept;
  FolderLock& operator=(FolderLock&&) = delete;
  FolderLock(const FolderLock&) = delete;
  ~FolderLock();

  const std::filesystem::path& lock_file() const { return lock_file_; }

 private:
  FolderLock(std::filesystem::path lock_file, int fd) : lock_file_(std::move(lock_file)), fd_(fd) {}

  std::filesystem::path lock_file_;
  int fd_ = -1;
};

// PARENT/.NAME.lock for `folder` (trailing separators ignored).
std::filesystem::path LockFileFor(const std::filesystem::path& folder);

}  // namespace svbtdf::common
