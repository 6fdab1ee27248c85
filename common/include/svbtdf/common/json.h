#pragma once
// Reading the JSON files users hand in (session.json, plan.json, calibration.json, material.json,
// truth manifests, ...). Every reader parses through here, so that any syntax error becomes one
// message naming the file, and so that nesting is bounded: nlohmann's parser is iterative, but
// copying, comparing or dumping a value recurses, and 150,000 nested [] overflow the stack.

#include <filesystem>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace svbtdf::common {

// Deeper than any svbtdf format needs (the deepest, a capture plan, nests 5 levels).
inline constexpr int kMaxJsonDepth = 64;

// Parses `text`. A syntax error, a number beyond double's range or nesting deeper than
// kMaxJsonDepth throws common::Error(kFormat) naming `subject`: "SUBJECT: is not valid JSON: ...".
nlohmann::json ParseJson(std::string_view text, const std::string& subject);

// ReadTextFile(path), then ParseJson naming the path.
nlohmann::json ReadJsonFile(const std::filesystem::path& path);

}  // namespace svbtdf::common
