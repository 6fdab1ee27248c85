#include "svbtdf/session/session.h"

#include <fcntl.h>
#include <unistd.h>
#include <zlib.h>

#include <cerrno>
#include <cmath>
#include <chrono>
#include <cstring>
#include <ctime>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <type_traits>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/json.h"
#include "svbtdf/common/durable_log.h"
#include "svbtdf/common/error.h"

namespace svbtdf::session {
namespace fs = std::filesystem;
namespace {

constexpr const char* kManifest = "session.json";
constexpr const char* kPlan = "plan.json";
constexpr const char* kJournal = "journal.jsonl";

std::string UtcNow() {
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm utc{};
  gmtime_r(&now, &utc);
  char buffer[32];
  std::strftime(buffer, sizeof buffer, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return buffer;
}

// Keys are short ASCII paths: letters, digits, '_', '-', '.', separated by '/', no "..".
void RequireValidKey(const std::string& key, const std::string& source) {
  static const std::regex pattern(R"([A-Za-z0-9_\-]+(\.[A-Za-z0-9_\-]+)*(/[A-Za-z0-9_\-]+(\.[A-Za-z0-9_\-]+)*)*)");
  if (key.empty() || key.size() > 200 || !std::regex_match(key, pattern)) {
    common::ThrowFormatError(source, "invalid capture key '" + key.substr(0, 80) + "'");
  }
}

template <typename T>
T Field(const nlohmann::json& object, const char* name, const std::string& source) {
  if (!object.is_object() || !object.contains(name)) common::ThrowFormatError(source, std::string("missing field '") + name + "'");
  // nlohmann converts 1.5 to the integer 1 and -1 to a huge unsigned: counts must be whole.
  if constexpr (std::is_integral_v<T>) {
    const nlohmann::json& value = object.at(name);
    if (!value.is_number_integer() || (std::is_unsigned_v<T> && !value.is_number_unsigned())) {
      common::ThrowFormatError(source, std::string("field '") + name + "' must be a whole number" +
                                           (std::is_unsigned_v<T> ? " >= 0" : "") + ", got " + value.dump());
    }
  }
  try {
    return object.at(name).get<T>();
  } catch (const nlohmann::json::exception&) {
    common::ThrowFormatError(source, std::string("field '") + name + "' has the wrong type");
  }
}

}  // namespace

uint32_t FileCrc32(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) common::ThrowIoError(path.string(), "cannot be read");
  uLong crc = crc32(0L, Z_NULL, 0);
  char buffer[1 << 16];
  while (in) {
    in.read(buffer, sizeof buffer);
    if (in.gcount() > 0) crc = crc32(crc, reinterpret_cast<const Bytef*>(buffer), static_cast<uInt>(in.gcount()));
  }
  return static_cast<uint32_t>(crc);
}

std::string Session::FileForKey(const std::string& key) { return "images/" + key + ".png"; }

std::string SessionVerification::Summary() const {
  std::ostringstream out;
  const auto list = [&](const char* what, const std::vector<std::string>& keys) {
    if (keys.empty()) return;
    out << keys.size() << " " << what << " (";
    for (size_t k = 0; k < keys.size() && k < 5; ++k) out << (k ? ", " : "") << keys[k];
    out << (keys.size() > 5 ? ", ..." : "") << "); ";
  };
  list("missing", missing);
  list("corrupt", corrupt);
  list("duplicated", duplicated);
  list("unexpected", unexpected);
  std::string text = out.str();
  return text.empty() ? "complete and intact" : text.substr(0, text.size() - 2);
}

Session Session::Create(const fs::path& folder, const nlohmann::json& rig, const std::vector<std::string>& planned_keys) {
  RigDescription description = ParseRigDescription(rig, (folder / kManifest).string() + " (new)");
  if (fs::exists(folder) && (!fs::is_directory(folder) || !fs::is_empty(folder))) {
    common::ThrowInvalidInput(folder.string(), "exists and is not empty; an existing session is never overwritten",
                 "choose a new output folder, or resume with the same command");
  }
  std::set<std::string> unique;
  for (const std::string& key : planned_keys) {
    RequireValidKey(key, "plan");
    if (!unique.insert(key).second) common::ThrowInvalidInput("plan", "capture key '" + key + "' is planned twice");
  }
  Session session;
  session.folder_ = folder;
  session.rig_json_ = rig;
  session.rig_ = std::move(description);
  session.planned_keys_ = planned_keys;
  session.planned_.insert(planned_keys.begin(), planned_keys.end());
  const nlohmann::json manifest = {{"format", "svbtdf-session"}, {"version", kSessionFormatVersion},
                                   {"created", UtcNow()},        {"software", "svbtdf"},
                                   {"rig", rig}};
  // Made whole under a temporary name and renamed into place, so that a kill leaves either no
  // session or a complete empty one, never a folder that every rerun refuses.
  common::CreateFolderAtomically(folder, [&](const fs::path& staging) {
    fs::create_directories(staging / "images");
    common::WriteTextAtomically(staging / kPlan, nlohmann::json({{"captures", planned_keys}}).dump(1) + "\n", false);
    common::WriteTextAtomically(staging / kManifest, manifest.dump(2) + "\n", false);
  });
  return session;
}

Session Session::Open(const fs::path& folder) {
  if (!fs::is_directory(folder)) common::ThrowIoError(folder.string(), "is not a session folder (does not exist)");
  Session session;
  session.folder_ = folder;
  const fs::path manifest_path = folder / kManifest;
  const nlohmann::json manifest = common::ReadJsonFile(manifest_path);
  if (Field<std::string>(manifest, "format", manifest_path.string()) != "svbtdf-session") {
    common::ThrowFormatError(manifest_path.string(), "is not an svbtdf session manifest");
  }
  const int version = Field<int>(manifest, "version", manifest_path.string());
  if (version != kSessionFormatVersion) {
    common::ThrowFormatError(manifest_path.string(), "has session format version " + std::to_string(version) +
                                                 "; this svbtdf reads version " + std::to_string(kSessionFormatVersion));
  }
  session.rig_json_ = manifest.value("rig", nlohmann::json::object());
  session.rig_ = ParseRigDescription(session.rig_json_, manifest_path.string());
  const fs::path plan_path = folder / kPlan;
  session.planned_keys_ = Field<std::vector<std::string>>(common::ReadJsonFile(plan_path), "captures", plan_path.string());
  for (const std::string& key : session.planned_keys_) RequireValidKey(key, plan_path.string());
  session.planned_.insert(session.planned_keys_.begin(), session.planned_keys_.end());
  session.ReadJournal();
  return session;
}

void Session::ReadJournal() {
  entries_.clear();
  index_.clear();
  // A last line cut short by a crash during its append is left out (and cut off before the
  // next append): its image counts as not captured, and a resumed capture replaces it.
  journal_ = common::DurableLog::Open(folder_ / kJournal, common::IsJsonObjectLine);
  const std::vector<std::string>& lines = journal_->lines();
  for (size_t n = 0; n < lines.size(); ++n) {
    const std::string where = journal_->path().string() + ":" + std::to_string(n + 1);
    if (lines[n].empty()) continue;
    nlohmann::json object;
    try {
      object = common::ParseJson(lines[n], where);
    } catch (const common::Error&) {
      common::ThrowFormatError(where, "is not a valid journal line");
    }
    SessionEntry entry;
    entry.key = Field<std::string>(object, "key", where);
    RequireValidKey(entry.key, where);
    entry.file = Field<std::string>(object, "file", where);
    if (entry.file != FileForKey(entry.key)) common::ThrowFormatError(where, "file does not match the key");
    entry.bytes = Field<uint64_t>(object, "bytes", where);
    entry.crc32 = Field<uint32_t>(object, "crc32", where);
    entry.exposure_s = Field<double>(object, "exposure_s", where);
    entry.gain = Field<double>(object, "gain", where);
    if (object.contains("time")) entry.time = Field<std::string>(object, "time", where);
    if (object.contains("presented_s")) entry.presented_s = Field<double>(object, "presented_s", where);
    index_.emplace(entry.key, entries_.size());
    entries_.push_back(std::move(entry));
  }
}

std::vector<std::string> Session::PlannedKeys(CaptureKind kind) const {
  std::vector<std::string> keys;
  for (const std::string& key : planned_keys_) {
    const std::optional<CaptureKey> parsed = CaptureKey::Parse(key);
    if (parsed && parsed->kind == kind) keys.push_back(key);
  }
  return keys;
}

const SessionEntry& Session::Entry(const std::string& key) const {
  const auto it = index_.find(key);
  if (it == index_.end()) common::ThrowIoError((folder_ / FileForKey(key)).string(), "is not in the session journal", "is the session complete? run 'svbtdf session verify'");
  return entries_[it->second];
}

void Session::AddImage(const std::string& key, const common::CameraImage& image, double exposure_s, double gain,
                       double presented_s) {
  RequireValidKey(key, "capture");
  if (Contains(key)) common::ThrowIoError(key, "is captured already; a capture is never overwritten");
  if (!planned_.count(key)) {
    common::ThrowInvalidInput(key, "is not in the session's plan");
  }
  const fs::path file = folder_ / FileForKey(key);
  std::error_code error;
  fs::create_directories(file.parent_path(), error);
  if (error) common::ThrowIoError(file.parent_path().string(), "cannot create: " + error.message());
  // A file without a journal line is left over from a crash mid-capture: replace it.
  common::WriteCameraImage(file, image, /*overwrite=*/true);
  SessionEntry entry{key, FileForKey(key), fs::file_size(file), FileCrc32(file), exposure_s, gain, UtcNow(), presented_s};
  // The writer checks every byte it writes; this is the last line of defence for the journal,
  // which must never vouch for an image that is not there.
  if (entry.bytes == 0) common::ThrowIoError(file.string(), "was written empty; it is not journalled", "is the disk full?");
  nlohmann::json line = {{"key", entry.key},   {"file", entry.file},       {"bytes", entry.bytes},
                         {"crc32", entry.crc32}, {"exposure_s", exposure_s}, {"gain", gain},
                         {"time", entry.time}};
  if (std::isfinite(presented_s)) line["presented_s"] = presented_s;
  if (!journal_) journal_ = common::DurableLog::Open(folder_ / kJournal, common::IsJsonObjectLine);
  journal_->Append(line.dump());
  index_.emplace(key, entries_.size());
  entries_.push_back(std::move(entry));
}

common::CameraImage Session::ReadImage(const std::string& key, bool check_crc) const {
  const SessionEntry& entry = Entry(key);
  const fs::path file = folder_ / entry.file;
  std::error_code error;
  const uint64_t size = fs::file_size(file, error);
  if (error) common::ThrowIoError(file.string(), "is journalled but missing", "run 'svbtdf session verify'");
  if (size != entry.bytes || (check_crc && FileCrc32(file) != entry.crc32)) {
    common::ThrowFormatError(file.string(), "does not match its journal entry (corrupt)", "re-capture it: resume the session");
  }
  common::CameraImage image = common::ReadCameraImage(file);
  RequireMatchesRig(key, image, file.string());
  return image;
}

// An 8-bit PNG, a JPEG or a colour image where the rig's camera stores 12-bit grey frames would
// be processed into a silently wrong material: every image must be what the rig says it takes.
void Session::RequireMatchesRig(const std::string& key, const common::CameraImage& image, const std::string& file) const {
  const RigCamera& camera = rig_.camera;
  const auto refuse = [&](const std::string& what, const std::string& expected) {
    common::ThrowFormatError(file, "is " + what + " but the session's camera (session.json) stores " + expected,
                             "the image was replaced or written by another tool: re-capture it");
  };
  if (camera.bit_depth > 8 && image.bits_per_sample <= 8) {
    refuse("an 8-bit image", std::to_string(camera.bit_depth) + "-bit images");
  }
  if (camera.channels > 0 && image.channels != camera.channels) {
    refuse("a " + std::to_string(image.channels) + "-channel image", std::to_string(camera.channels) + "-channel images");
  }
  // Board views of a camera that crops to a window are whole-sensor frames.
  const bool whole_sensor = !camera.sensor.whole_sensor() && key.rfind("board/", 0) == 0;
  const int width = whole_sensor ? camera.sensor.sensor_width : camera.width;
  const int height = whole_sensor ? camera.sensor.sensor_height : camera.height;
  if (width > 0 && height > 0 && (image.width != width || image.height != height)) {
    refuse(std::to_string(image.width) + "x" + std::to_string(image.height) + " pixels",
           std::to_string(width) + "x" + std::to_string(height) + "-pixel images");
  }
}

namespace {

bool Decodes(const fs::path& file) {
  try {
    common::ReadCameraImage(file);
    return true;
  } catch (const common::Error&) {
    return false;
  }
}

}  // namespace

SessionVerification Session::Verify(bool check_crc, bool decode) const {
  SessionVerification report;
  const std::set<std::string> planned(planned_keys_.begin(), planned_keys_.end());
  std::set<std::string> seen;
  for (const SessionEntry& entry : entries_) {
    if (!seen.insert(entry.key).second) report.duplicated.push_back(entry.key);
    if (!planned.count(entry.key)) report.unexpected.push_back(entry.key);
    const fs::path file = folder_ / entry.file;
    std::error_code error;
    const uint64_t size = fs::file_size(file, error);
    if (error || size == 0 || size != entry.bytes || (check_crc && FileCrc32(file) != entry.crc32) ||
        (decode && !Decodes(file))) {
      report.corrupt.push_back(entry.key);
    }
  }
  for (const std::string& key : planned_keys_) {
    if (!seen.count(key)) report.missing.push_back(key);
  }
  return report;
}

}  // namespace svbtdf::session
