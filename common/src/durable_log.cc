#include "svbtdf/common/durable_log.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <nlohmann/json.hpp>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/json.h"

namespace svbtdf::common {
namespace fs = std::filesystem;
namespace {

// One write(2) of the whole line and its newline, then fsync: a crash leaves all of it, a
// prefix of it, or none of it.
void AppendBytesDurably(const fs::path& path, const std::string& bytes) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) ThrowIoError(path.string(), std::string("cannot open for appending: ") + std::strerror(errno));
  const ssize_t written = ::write(fd, bytes.data(), bytes.size());
  const bool ok = written == static_cast<ssize_t>(bytes.size()) && ::fsync(fd) == 0;
  const int saved = errno;
  ::close(fd);
  if (!ok) ThrowIoError(path.string(), std::string("append failed: ") + std::strerror(saved), "is the disk full?");
}

}  // namespace

bool IsJsonObjectLine(std::string_view line) {
  try {
    return ParseJson(line, "journal line").is_object();
  } catch (const Error&) {  // parse errors, number overflow, nesting beyond kMaxJsonDepth
    return false;
  }
}

DurableLog DurableLog::Open(fs::path path, const WholeLine& whole) {
  DurableLog log(std::move(path));
  if (!fs::exists(log.path_)) return log;
  const std::string text = ReadTextFile(log.path_);
  size_t start = 0;
  while (start < text.size()) {
    const size_t end = text.find('\n', start);
    if (end == std::string::npos) {
      const std::string_view tail(text.data() + start, text.size() - start);
      if (whole && whole(tail)) {
        log.lines_.emplace_back(tail);
        log.needs_newline_ = true;
      } else {
        log.truncate_to_ = start;
        log.had_torn_tail_ = true;
      }
      break;
    }
    log.lines_.emplace_back(text, start, end - start);
    start = end + 1;
  }
  return log;
}

void DurableLog::RepairTail() {
  if (truncate_to_) {
    std::error_code error;
    fs::resize_file(path_, *truncate_to_, error);
    if (error) ThrowIoError(path_.string(), "cannot cut off its torn last line: " + error.message());
    truncate_to_.reset();
  }
  if (needs_newline_) {
    AppendBytesDurably(path_, "\n");
    needs_newline_ = false;
  }
}

void DurableLog::Append(std::string_view line) {
  if (line.find('\n') != std::string_view::npos) ThrowInvalidInput(path_.string(), "a log line may not contain a newline");
  RepairTail();
  std::string bytes(line);
  bytes += '\n';
  AppendBytesDurably(path_, bytes);
}

}  // namespace svbtdf::common
