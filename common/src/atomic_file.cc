#include "svbtdf/common/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <random>
#include <sstream>
#include <vector>

#include "svbtdf/common/error.h"
#include "svbtdf/common/fault_injection.h"

namespace svbtdf::common {
namespace fs = std::filesystem;
namespace {

constexpr std::string_view kTemporaryMarker = ".tmp-";

// Opens `path` for syncing; a folder is synced so that a rename in it is durable.
void FsyncPath(const fs::path& path, bool is_directory) {
  const int fd = ::open(path.c_str(), (is_directory ? (O_RDONLY | O_DIRECTORY) : O_RDONLY) | O_CLOEXEC);
  if (fd < 0) ThrowSystemError(path.string(), "cannot open to sync", errno);
  try {
    SyncOrThrow(fd, path);
  } catch (...) {
    ::close(fd);
    throw;
  }
  ::close(fd);
}

fs::path TempSibling(const fs::path& path) {
  static thread_local std::mt19937_64 rng{std::random_device{}()};
  std::ostringstream name;
  name << "." << path.filename().string() << kTemporaryMarker << std::hex << rng();
  return path.parent_path() / name.str();
}

bool IsTemporaryName(const std::string& name) {
  return name.size() > 1 && name[0] == '.' && name.find(kTemporaryMarker) != std::string::npos;
}

void RenameOrThrow(const fs::path& from, const fs::path& to, bool overwrite) {
  FailOrKillIfInjected(to.string(), "cannot rename into place");  // a kill leaves the temporary file
  if (!overwrite) {
    // link() fails if the target appeared meanwhile, so a concurrent writer cannot be clobbered.
    if (::link(from.c_str(), to.c_str()) != 0) ThrowSystemError(to.string(), "cannot create", errno);
    fs::remove(from);
  } else if (::rename(from.c_str(), to.c_str()) != 0) {
    ThrowSystemError(to.string(), "cannot rename into place", errno);
  }
}

uint64_t SizeOf(const fs::path& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) ThrowSystemError(path.string(), "cannot read its size", errno);
  return static_cast<uint64_t>(st.st_size);
}

}  // namespace

void WriteAllOrThrow(int fd, const void* data, size_t size, const fs::path& path, int64_t offset) {
  const auto* p = static_cast<const char*>(data);
  switch (NextDurableOperation()) {
    case FaultAction::kProceed:
      break;
    case FaultAction::kFail:
      ThrowSystemError(path.string(), "cannot write", ENOSPC);
    case FaultAction::kKill:  // a crash mid-write: half the bytes reach the file
      if (size / 2 > 0) {
        [[maybe_unused]] const ssize_t n = offset < 0 ? ::write(fd, p, size / 2) : ::pwrite(fd, p, size / 2, offset);
      }
      KillProcessNow();
  }
  while (size > 0) {
    const ssize_t n = offset < 0 ? ::write(fd, p, size) : ::pwrite(fd, p, size, static_cast<off_t>(offset));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) ThrowSystemError(path.string(), "cannot write", errno);
    if (n == 0) ThrowSystemError(path.string(), "cannot write", ENOSPC);  // no progress and no reason: the disk
    p += n;
    size -= static_cast<size_t>(n);
    if (offset >= 0) offset += n;
  }
}

void SyncOrThrow(int fd, const fs::path& path) {
  FailOrKillIfInjected(path.string(), "fsync failed");
  if (::fsync(fd) != 0) ThrowSystemError(path.string(), "fsync failed", errno);
}

namespace {
// The one atomic write: `write` produces the temporary file, which is checked, synced and renamed.
void WriteAtomically(const fs::path& path, const std::function<void(const fs::path&)>& write, bool overwrite,
                     bool empty_is_failure) {
  const fs::path folder = path.has_parent_path() ? path.parent_path() : fs::path(".");
  if (!fs::is_directory(folder)) ThrowIoError(folder.string(), "folder does not exist");
  if (!overwrite && fs::exists(path)) {
    ThrowIoError(path.string(), "already exists and will not be overwritten",
                 "choose another output path or remove the file yourself");
  }
  const fs::path temp = TempSibling(folder / path.filename());
  try {
    write(temp);
    // Writers that buffer (stdio under a library) may lose a full disk's error; an empty file is
    // never what anyone meant to write.
    if (empty_is_failure && SizeOf(temp) == 0) ThrowSystemError(path.string(), "cannot write", ENOSPC);
    FsyncPath(temp, /*is_directory=*/false);
    RenameOrThrow(temp, path, overwrite);
    FsyncPath(folder, /*is_directory=*/true);
  } catch (...) {
    std::error_code ignored;
    fs::remove(temp, ignored);
    throw;
  }
}
}  // namespace

void WriteFileAtomically(const fs::path& path, const std::function<void(const fs::path&)>& write,
                         bool overwrite) {
  WriteAtomically(path, write, overwrite, /*empty_is_failure=*/true);
}

void WriteBytesAtomically(const fs::path& path, std::string_view bytes, bool overwrite) {
  WriteAtomically(
      path,
      [&](const fs::path& temp) {
        const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
        if (fd < 0) ThrowSystemError(path.string(), "cannot create", errno);
        try {
          WriteAllOrThrow(fd, bytes.data(), bytes.size(), path);
        } catch (...) {
          ::close(fd);
          throw;
        }
        if (::close(fd) != 0) ThrowSystemError(path.string(), "cannot write", errno);
        // What is on disk is what was meant, byte for byte in length, before it gets its name.
        if (SizeOf(temp) != bytes.size()) ThrowSystemError(path.string(), "cannot write", ENOSPC);
      },
      overwrite, /*empty_is_failure=*/false);
}

void WriteTextAtomically(const fs::path& path, std::string_view contents, bool overwrite) {
  WriteBytesAtomically(path, contents, overwrite);
}

void CreateFolderAtomically(const fs::path& folder, const std::function<void(const fs::path&)>& fill) {
  const fs::path target = WithoutTrailingSeparators(folder);
  const fs::path parent = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::error_code error;
  fs::create_directories(parent, error);
  if (error) ThrowSystemError(parent.string(), "cannot create", error.value());
  const std::string leftover_prefix = "." + target.filename().string() + std::string(kTemporaryMarker);
  for (const fs::directory_entry& entry : fs::directory_iterator(parent, error)) {
    if (entry.path().filename().string().rfind(leftover_prefix, 0) == 0) fs::remove_all(entry.path(), error);
  }
  if (fs::exists(target) && (!fs::is_directory(target) || !fs::is_empty(target))) {
    ThrowIoError(target.string(), "exists and is not empty; it is never overwritten");
  }
  const fs::path staging = TempSibling(target);
  try {
    if (!fs::create_directory(staging, error)) ThrowSystemError(staging.string(), "cannot create", error.value());
    fill(staging);
    FsyncPath(staging, /*is_directory=*/true);
    RenameOrThrow(staging, target, /*overwrite=*/true);
    FsyncPath(parent, /*is_directory=*/true);
  } catch (const Error& e) {
    fs::remove_all(staging, error);
    // The user knows the folder by its name, not by the staging folder's.
    std::string subject = e.subject();
    if (subject.rfind(staging.string(), 0) == 0) subject = target.string() + subject.substr(staging.string().size());
    throw Error(e.kind(), subject, e.problem(), e.hint());
  } catch (...) {
    fs::remove_all(staging, error);
    throw;
  }
}

int RemoveStaleTemporaryFiles(const fs::path& folder) {
  std::vector<fs::path> leftovers;
  std::error_code error;
  for (fs::recursive_directory_iterator it(folder, fs::directory_options::skip_permission_denied, error), end;
       !error && it != end; it.increment(error)) {
    if (!IsTemporaryName(it->path().filename().string())) continue;
    leftovers.push_back(it->path());
    if (it->is_directory(error)) it.disable_recursion_pending();  // a staging folder goes whole
  }
  int removed = 0;
  for (const fs::path& path : leftovers) removed += fs::remove_all(path, error) > 0;
  return removed;
}

uint64_t FreeSpaceAt(const fs::path& folder) {
  fs::path existing = fs::absolute(folder);
  while (!fs::exists(existing) && existing.has_parent_path() && existing != existing.parent_path()) {
    existing = existing.parent_path();
  }
  std::error_code error;
  const fs::space_info space = fs::space(existing, error);
  if (error) ThrowIoError(existing.string(), "cannot query its free space: " + error.message());
  return space.available;
}

fs::path WithoutTrailingSeparators(const fs::path& path) {
  std::string text = path.string();
  while (text.size() > 1 && text.back() == fs::path::preferred_separator) text.pop_back();
  return text;
}

std::string ReadTextFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) ThrowIoError(path.string(), "cannot open for reading", "does the file exist?");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) ThrowIoError(path.string(), "read failed");
  return buffer.str();
}

}  // namespace svbtdf::common
