#pragma once
// A capture session on disk (docs/session-format.md, version 1): what a lab capture and the
// simulator write and what calibration reads.
//
//   SESSION/session.json    manifest: format, version, rig description, software
//   SESSION/plan.json       the captures that make the session complete, by key
//   SESSION/journal.jsonl   append-only: one line per stored image, with its size and CRC-32
//   SESSION/images/<key>.png
//
// An image counts as captured only once its journal line is on disk: images are written to a
// temporary file, fsync'ed and renamed, and only then journalled (fsync'ed too). A crash leaves
// at worst an image without a journal line, which a resumed capture replaces. Nothing in the
// journal is ever overwritten.

#include <cstdint>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include <nlohmann/json.hpp>

#include "svbtdf/common/durable_log.h"
#include "svbtdf/common/image_io.h"
#include "svbtdf/session/capture_key.h"
#include "svbtdf/session/rig.h"

namespace svbtdf::session {

inline constexpr int kSessionFormatVersion = 1;

struct SessionEntry {
  std::string key;        // e.g. "dot/q0012/e1/r0"
  std::string file;       // relative to the session folder
  uint64_t bytes = 0;
  uint32_t crc32 = 0;     // of the file's bytes (zlib's CRC-32)
  double exposure_s = 0.0;
  double gain = 1.0;
  std::string time;       // UTC, ISO 8601
  // When the display presented the pattern (steady/monotonic clock seconds of the capturing run;
  // NaN when not journalled: sessions before it, or images stored without a display).
  double presented_s = std::numeric_limits<double>::quiet_NaN();
};

struct SessionVerification {
  std::vector<std::string> missing;     // planned but not journalled
  std::vector<std::string> corrupt;     // journalled but the file is absent, its size/CRC differs or it does not decode
  std::vector<std::string> duplicated;  // journalled more than once
  std::vector<std::string> unexpected;  // journalled but not planned
  // Unexpected keys count too: a journal that holds captures its plan does not means a damaged plan.
  bool complete() const { return missing.empty() && corrupt.empty() && duplicated.empty() && unexpected.empty(); }
  std::string Summary() const;
};

class Session {
 public:
  // Creates SESSION with its manifest and plan. Throws svbtdf::Error(kIo) when the folder exists
  // and is not empty: an existing session is never overwritten.
  static Session Create(const std::filesystem::path& folder, const nlohmann::json& rig,
                        const std::vector<std::string>& planned_keys);
  // Opens an existing session, reading and checking its manifest, plan and journal. A last
  // journal line cut short by a crash is ignored; any other malformed line is an error naming the
  // file and line.
  static Session Open(const std::filesystem::path& folder);

  const std::filesystem::path& folder() const { return folder_; }
  // The manifest's rig description, typed; rig_json() as written (for tools that show it).
  const RigDescription& rig() const { return rig_; }
  const nlohmann::json& rig_json() const { return rig_json_; }
  const std::vector<std::string>& planned_keys() const { return planned_keys_; }
  // The planned keys of one kind, in plan order.
  std::vector<std::string> PlannedKeys(CaptureKind kind) const;
  const std::vector<SessionEntry>& entries() const { return entries_; }

  bool Contains(const std::string& key) const { return index_.count(key) > 0; }
  const SessionEntry& Entry(const std::string& key) const;  // throws when not journalled

  // Stores a captured image under `key` and journals it. Throws when the key is journalled
  // already or not planned.
  // `presented_s`: when the display presented the pattern the image was taken of (monotonic
  // seconds, journalled as `presented_s`); NaN: not known.
  void AddImage(const std::string& key, const common::CameraImage& image, double exposure_s, double gain,
                double presented_s = std::numeric_limits<double>::quiet_NaN());
  // Reads a journalled image, checking its size (and CRC when `check_crc`), and its bit depth,
  // channels and size against the rig's camera (a kFormat error naming the file otherwise).
  common::CameraImage ReadImage(const std::string& key, bool check_crc = false) const;

  // Checks every journalled image's size and (with `check_crc`) CRC-32; with `decode` also
  // decodes each one, so that an image journalled with its own damage (a CRC of a cut-short
  // file) is found too. Slow: a full decode of every image.
  SessionVerification Verify(bool check_crc = true, bool decode = false) const;

  // images/<key>.png with the key's slashes kept as folders.
  static std::string FileForKey(const std::string& key);

 private:
  Session() = default;
  void ReadJournal();
  void RequireMatchesRig(const std::string& key, const common::CameraImage& image, const std::string& file) const;

  std::filesystem::path folder_;
  RigDescription rig_;
  nlohmann::json rig_json_;
  std::vector<std::string> planned_keys_;
  std::unordered_set<std::string> planned_;  // the same keys, for lookups
  std::vector<SessionEntry> entries_;
  std::unordered_map<std::string, size_t> index_;  // key -> first entry
  std::optional<common::DurableLog> journal_;  // journal.jsonl, repaired before the next append
};

// CRC-32 of a file's bytes; throws naming the file when it cannot be read.
uint32_t FileCrc32(const std::filesystem::path& path);

}  // namespace svbtdf::session
