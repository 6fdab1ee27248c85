#include "svbtdf/common/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <random>
#include <sstream>

#include "svbtdf/common/error.h"

namespace svbtdf::common {
namespace fs = std::filesystem;
namespace {

void FsyncPath(const fs::path& path, bool is_directory) {
  const int fd = ::open(path.c_str(), is_directory ? (O_RDONLY | O_DIRECTORY) : O_RDONLY);
  if (fd < 0) ThrowIoError(path.string(), std::string("cannot open to sync: ") + std::strerror(errno));
  const int rc = ::fsync(fd);
  const int saved_errno = errno;
  ::close(fd);
  if (rc != 0) ThrowIoError(path.string(), std::string("fsync failed: ") + std::strerror(saved_errno),
                            "is the disk full or removed?");
}

fs::path TempSibling(const fs::path& path) {
  static thread_local std::mt19937_64 rng{std::random_device{}()};
  std::ostringstream name;
  name << "." << path.filename().string() << ".tmp-" << std::hex << rng();
  return path.parent_path() / name.str();
}

}  // namespace

void WriteFileAtomically(const fs::path& path, const std::function<void(const fs::path&)>& write,
                         bool overwrite) {
  const fs::path folder = path.has_parent_path() ? path.parent_path() : fs::path(".");
  if (!fs::is_directory(folder)) ThrowIoError(folder.string(), "folder does not exist");
  if (!overwrite && fs::exists(path)) {
    ThrowIoError(path.string(), "already exists and will not be overwritten",
                 "choose another output path or remove the file yourself");
  }
  const fs::path temp = TempSibling(folder / path.filename());
  try {
    write(temp);
    FsyncPath(temp, /*is_directory=*/false);
    if (!overwrite) {
      // link() fails if the target appeared meanwhile, so a concurrent writer cannot be clobbered.
      if (::link(temp.c_str(), path.c_str()) != 0) {
        ThrowIoError(path.string(), std::string("cannot create: ") + std::strerror(errno));
      }
      fs::remove(temp);
    } else {
      fs::rename(temp, path);
    }
    FsyncPath(folder, /*is_directory=*/true);
  } catch (...) {
    std::error_code ignored;
    fs::remove(temp, ignored);
    throw;
  }
}

void WriteTextAtomically(const fs::path& path, std::string_view contents, bool overwrite) {
  WriteFileAtomically(
      path,
      [&](const fs::path& temp) {
        std::ofstream out(temp, std::ios::binary);
        out.write(contents.data(), static_cast<std::streamsize>(contents.size()));
        out.close();
        if (!out) ThrowIoError(path.string(), "write failed", "is the disk full?");
      },
      overwrite);
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
