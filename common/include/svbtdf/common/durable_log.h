#pragma once
// An append-only log of text lines that survives a crash at any instant: the house's one
// journal (the capture session's journal.jsonl, the slice store's progress.jsonl, the fit's
// checkpoint). Each append writes its line and newline with one write(2) and fsyncs, so a crash
// leaves the lines before it intact and at worst a torn last line, which Open repairs.
//
// What the lines mean is the caller's: the log only knows where lines end.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace svbtdf::common {

class DurableLog {
 public:
  // Says whether an unterminated last line is whole (a write torn just before its newline).
  using WholeLine = std::function<bool(std::string_view line)>;

  // Reads the log at `path` (absent: no lines yet; created by the first Append). Its lines are
  // every line ending in a newline (empty ones included, so that line n is lines()[n - 1]) and an
  // unterminated last line when `whole` accepts it. Any other unterminated tail is torn: it is
  // left out and cut off before the next append, so that the next line stands on its own.
  static DurableLog Open(std::filesystem::path path, const WholeLine& whole = {});

  const std::filesystem::path& path() const { return path_; }
  // The lines Open read (appended lines are not kept: a session journal can be long).
  const std::vector<std::string>& lines() const { return lines_; }
  // True when Open found a torn tail (left out of lines()).
  bool had_torn_tail() const { return had_torn_tail_; }

  // Appends `line` (which must not contain a newline) and fsyncs the file. Throws
  // Error(kIo) naming the file when the disk refuses. Not thread-safe: callers serialise.
  void Append(std::string_view line);
  // Appends `lines` with one write(2) and one fsync: a group commit, for callers whose records
  // come faster than a disk syncs. A crash keeps a prefix of them, at worst with a torn last line.
  void Append(const std::vector<std::string>& lines);

 private:
  explicit DurableLog(std::filesystem::path path) : path_(std::move(path)) {}
  void RepairTail();

  std::filesystem::path path_;
  std::vector<std::string> lines_;
  std::optional<uintmax_t> truncate_to_;  // the torn tail starts here, until it is cut off
  bool needs_newline_ = false;            // the last line is whole but lost its newline
  bool had_torn_tail_ = false;
};

// A WholeLine for logs of JSON objects: the line parses as an object. (No proper prefix of an
// object is one, whereas "1" is a prefix of "12": logs of bare values cannot tell.)
bool IsJsonObjectLine(std::string_view line);

}  // namespace svbtdf::common
