#pragma once
// Reading the JSON files users hand in (session.json, plan.json, calibration.json, material.json,
// truth manifests, ...). Every reader parses through here, so that any syntax error becomes one
// message naming the file, and so that nesting is bounded: nlohmann's parser is iterative, but
// copying, comparing or dumping a value recurses, and 150,000 nested [] overflow the stack.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "svbtdf/common/error.h"

namespace svbtdf::common {

// Deeper than any svbtdf format needs (the deepest, a capture plan, nests 5 levels).
inline constexpr int kMaxJsonDepth = 64;

// Parses `text`. A syntax error, a number beyond double's range or nesting deeper than
// kMaxJsonDepth throws common::Error(kFormat) naming `subject`: "SUBJECT: is not valid JSON: ...".
nlohmann::json ParseJson(std::string_view text, const std::string& subject);

// ReadTextFile(path), then ParseJson naming the path.
nlohmann::json ReadJsonFile(const std::filesystem::path& path);

// ParseJson(text, subject), then `read(document)`. A value of an unexpected type deep inside
// (nlohmann's type_error or out_of_range, thrown by a reader's `get` or `at`) becomes one
// common::Error(kFormat) naming `subject`, "SUBJECT: is malformed: ...", with `hint`; the
// reader's own common::Errors pass through unchanged.
template <class Reader>
auto ParseJsonWith(std::string_view text, const std::string& subject, const std::string& hint, Reader&& read)
    -> decltype(read(std::declval<const nlohmann::json&>())) {
  const nlohmann::json document = ParseJson(text, subject);
  try {
    return read(document);
  } catch (const nlohmann::json::exception& e) {
    ThrowFormatError(subject, std::string("is malformed: ") + e.what(), hint);
  }
}

// `value` as an Int when it is a JSON integer that Int can hold; nothing for a float, a
// non-number or an integer out of Int's range. The one test behind every integer a reader takes
// from a file: nlohmann's get<int>() converts a JSON float with a C++ cast, which is undefined
// behaviour when the float is out of range (the fuzzer's width of 4.9e111).
template <class Int>
std::optional<Int> IntegerIfFits(const nlohmann::json& value) {
  static_assert(std::is_integral_v<Int>);
  const bool fits = value.is_number_unsigned()  ? std::in_range<Int>(value.get<uint64_t>())
                    : value.is_number_integer() ? std::in_range<Int>(value.get<int64_t>())
                                                : false;
  if (!fits) return std::nullopt;
  return value.get<Int>();
}

// IntegerIfFits, or one common::Error(kFormat): "SOURCE: has a 'NAME' that is not an integer ...".
template <class Int>
Int IntegerValue(const nlohmann::json& value, std::string_view name, const std::string& source) {
  const std::optional<Int> integer = IntegerIfFits<Int>(value);
  if (!integer) {
    ThrowFormatError(source, "has a '" + std::string(name) + "' that is not an integer of a sensible size: " +
                                 value.dump().substr(0, 40));
  }
  return *integer;
}

// IntegerValue of object.at(key) (a missing key throws nlohmann's out_of_range, as at() does).
template <class Int = int>
Int IntegerAt(const nlohmann::json& object, const char* key, const std::string& source) {
  return IntegerValue<Int>(object.at(key), key, source);
}

// An array of integers, each through IntegerValue.
template <class Int>
std::vector<Int> IntegerArrayAt(const nlohmann::json& object, const char* key, const std::string& source) {
  const nlohmann::json& array = object.at(key);
  if (!array.is_array()) ThrowFormatError(source, "has a '" + std::string(key) + "' that is not an array");
  std::vector<Int> values;
  values.reserve(array.size());
  for (const nlohmann::json& value : array) values.push_back(IntegerValue<Int>(value, key, source));
  return values;
}

// The string at `key` of `object`, or `fallback` when `object` is not an object, lacks `key` or
// holds something else there. For free-form notes a reader only passes on (a provenance's
// "session"), where a hand-edited value must not stop the work.
inline std::string StringOr(const nlohmann::json& object, const char* key, std::string fallback = {}) {
  if (!object.is_object()) return fallback;
  const auto found = object.find(key);
  return found != object.end() && found->is_string() ? found->get<std::string>() : fallback;
}

// Typed, range-checked access to one JSON object of a file a user writes (a capture plan, a rig
// description); every error is common::Error(kFormat) naming the file and the field, with `hint`
// (e.g. "see docs/capture.md for the plan format"). Unknown fields are refused, so that a
// misspelt setting is not silently replaced by its default. `prefix` is the object's path
// ("dots.") and `what` names the file's kind in messages ("plan": "is not a plan field").
class JsonFields {
 public:
  JsonFields(const nlohmann::json& object, std::string source, std::string prefix, const std::set<std::string>& known,
             std::string hint, std::string what);
  bool Has(const std::string& name) const { return object_.contains(name); }
  const nlohmann::json& Raw(const std::string& name) const;
  double Number(const std::string& name, double lo, double hi) const;
  double Number(const std::string& name, double lo, double hi, double fallback) const {
    return Has(name) ? Number(name, lo, hi) : fallback;
  }
  int Integer(const std::string& name, int lo, int hi) const;
  int Integer(const std::string& name, int lo, int hi, int fallback) const {
    return Has(name) ? Integer(name, lo, hi) : fallback;
  }
  std::string Text(const std::string& name, const std::string& fallback) const;
  bool Flag(const std::string& name, bool fallback) const;
  std::pair<double, double> Pair(const std::string& name, double lo, double hi) const;
  double CheckNumber(const nlohmann::json& value, const std::string& name, double lo, double hi) const;
  [[noreturn]] void Fail(const std::string& field, const std::string& problem) const;
  const std::string& prefix() const { return prefix_; }

 private:
  const nlohmann::json& object_;
  std::string source_;
  std::string prefix_;
  std::string hint_;
  std::string what_;
};

}  // namespace svbtdf::common
