#include "svbtdf/common/durable_log.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <nlohmann/json.hpp>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/fault_injection.h"
#include "svbtdf/common/json.h"

namespace svbtdf::common {
namespace fs = std::filesystem;
namespace {

// The line and its newline in one write (retried only if the kernel writes part of it), then
// fsync: a crash leaves all of it, a prefix of it, or none of it.
void AppendBytesDurably(const fs::path& path, const std::string& bytes) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) ThrowSystemError(path.string(), "cannot open for appending", errno);
  try {
    WriteAllOrThrow(fd, bytes.data(), bytes.size(), path);
    SyncOrThrow(fd, path);
  } catch (...) {
    ::close(fd);
    throw;
  }
  ::close(fd);
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

void DurableLog::Append(std::string_view line) { Append(std::vector<std::string>{std::string(line)}); }

void DurableLog::Append(const std::vector<std::string>& lines) {
  if (lines.empty()) return;
  std::string bytes;
  for (const std::string& line : lines) {
    if (line.find('\n') != std::string::npos) ThrowInvalidInput(path_.string(), "a log line may not contain a newline");
    bytes += line;
    bytes += '\n';
  }
  RepairTail();
  AppendBytesDurably(path_, bytes);
}

}  // namespace svbtdf::common
