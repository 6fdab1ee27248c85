#include "svbtdf/common/json.h"

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"

namespace svbtdf::common {
namespace {

// Thrown by the parser callback; caught below and turned into the file's message.
struct TooDeep {};

}  // namespace

nlohmann::json ParseJson(std::string_view text, const std::string& subject) {
  // The callback sees the depth of every value as it is read and stops the parse before the
  // deep value exists, so nothing recursive ever touches it.
  const nlohmann::json::parser_callback_t bound_depth = [](int depth, nlohmann::json::parse_event_t, nlohmann::json&) {
    if (depth > kMaxJsonDepth) throw TooDeep{};
    return true;
  };
  try {
    return nlohmann::json::parse(text.begin(), text.end(), bound_depth);
  } catch (const TooDeep&) {
    ThrowFormatError(subject, "is not valid JSON: nested deeper than " + std::to_string(kMaxJsonDepth) + " levels");
  } catch (const nlohmann::json::exception& e) {  // syntax errors, but also number overflow
    ThrowFormatError(subject, std::string("is not valid JSON: ") + e.what());
  }
}

nlohmann::json ReadJsonFile(const std::filesystem::path& path) { return ParseJson(ReadTextFile(path), path.string()); }

}  // namespace svbtdf::common
