#include "svbtdf/common/json.h"

#include <cmath>
#include <cstdio>

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

namespace {

std::string Short(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", v);
  return buffer;
}

}  // namespace

JsonFields::JsonFields(const nlohmann::json& object, std::string source, std::string prefix,
                       const std::set<std::string>& known, std::string hint, std::string what)
    : object_(object), source_(std::move(source)), prefix_(std::move(prefix)), hint_(std::move(hint)), what_(std::move(what)) {
  if (!object_.is_object()) Fail(prefix_.empty() ? "the " + what_ : prefix_, "must be a JSON object");
  for (const auto& item : object_.items()) {
    if (!known.count(item.key())) Fail(prefix_ + item.key(), "is not a " + what_ + " field (misspelt?)");
  }
}

const nlohmann::json& JsonFields::Raw(const std::string& name) const {
  if (!Has(name)) Fail(prefix_ + name, "is missing");
  return object_.at(name);
}

double JsonFields::Number(const std::string& name, double lo, double hi) const { return CheckNumber(Raw(name), name, lo, hi); }

int JsonFields::Integer(const std::string& name, int lo, int hi) const {
  const nlohmann::json& value = Raw(name);
  if (!value.is_number_integer()) Fail(prefix_ + name, "must be an integer");
  // An integer beyond int's range lies outside [lo, hi] too.
  const std::optional<int> v = IntegerIfFits<int>(value);
  if (!v || *v < lo || *v > hi) Fail(prefix_ + name, "must lie in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  return *v;
}

std::string JsonFields::Text(const std::string& name, const std::string& fallback) const {
  if (!Has(name)) return fallback;
  if (!object_.at(name).is_string()) Fail(prefix_ + name, "must be a string");
  return object_.at(name).get<std::string>();
}

bool JsonFields::Flag(const std::string& name, bool fallback) const {
  if (!Has(name)) return fallback;
  if (!object_.at(name).is_boolean()) Fail(prefix_ + name, "must be true or false");
  return object_.at(name).get<bool>();
}

std::pair<double, double> JsonFields::Pair(const std::string& name, double lo, double hi) const {
  const nlohmann::json& value = Raw(name);
  if (!value.is_array() || value.size() != 2) Fail(prefix_ + name, "must be a pair [x, y]");
  return {CheckNumber(value[0], name, lo, hi), CheckNumber(value[1], name, lo, hi)};
}

double JsonFields::CheckNumber(const nlohmann::json& value, const std::string& name, double lo, double hi) const {
  if (!value.is_number()) Fail(prefix_ + name, "must be a number");
  const double v = value.get<double>();
  if (!std::isfinite(v) || v < lo || v > hi) {
    Fail(prefix_ + name, "must lie in [" + Short(lo) + ", " + Short(hi) + "], got " + Short(v));
  }
  return v;
}

void JsonFields::Fail(const std::string& field, const std::string& problem) const {
  ThrowFormatError(source_, "field '" + field + "' " + problem, hint_);
}

}  // namespace svbtdf::common
