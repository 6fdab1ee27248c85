// Reading user-supplied JSON (common/json.h): one message naming the file for every kind of bad
// text, and nesting bounded before anything recursive can touch the value.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>

#include "expect_error.h"
#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/json.h"
#include "temp_folder.h"

namespace svbtdf::common {
namespace {

std::string Nested(int depth) { return std::string(depth, '[') + std::string(depth, ']'); }

TEST(Json, ParsesNestingUpToTheBound) {
  const nlohmann::json value = ParseJson("{\"a\": " + Nested(kMaxJsonDepth - 1) + "}", "x.json");
  const nlohmann::json copy = value;  // copies recurse: the bound keeps them shallow
  EXPECT_EQ(copy, value);
  EXPECT_TRUE(value.at("a").is_array());
}

// 150,000 nested [] crashed verify, calibrate, process, eval, compare and report (issue 15):
// nlohmann parses them iteratively, but the first copy of the value overflowed the stack.
TEST(Json, DeeperNestingIsAFormatErrorNamingTheFileNotACrash) {
  for (int depth : {kMaxJsonDepth + 1, 150000}) {
    svbtdf::testing::ExpectError(ErrorKind::kFormat, "session.json: is not valid JSON: nested deeper than 64 levels",
                                 [&] { ParseJson("{\"rig\": " + Nested(depth) + "}", "session.json"); });
  }
}

TEST(Json, SyntaxErrorsAndOverflowingNumbersNameTheFile) {
  for (const char* text : {"", "{", "{\"a\": 1,}", "[1e999]", "{\"a\": nan}", "\xff\xfe"}) {
    svbtdf::testing::ExpectError(ErrorKind::kFormat, "plan.json: is not valid JSON", [&] { ParseJson(text, "plan.json"); });
  }
}

TEST(Json, ReadJsonFileNamesThePath) {
  const svbtdf::testing::TempFolder folder("json_test");
  const auto path = folder.path() / "material.json";
  WriteTextAtomically(path, Nested(100000));
  svbtdf::testing::ExpectError(ErrorKind::kFormat, path.string() + ": is not valid JSON", [&] { ReadJsonFile(path); });
  WriteTextAtomically(path, "{\"format\": \"svbtdf-material\"}");
  EXPECT_EQ(ReadJsonFile(path).at("format"), "svbtdf-material");
  svbtdf::testing::ExpectError(ErrorKind::kIo, "missing.json", [&] { ReadJsonFile(folder.path() / "missing.json"); });
}

// nlohmann's get<int>() of 4.9e111 is a C++ cast out of range, undefined behaviour (the material
// fuzzer's finding); every integer a reader takes goes through IntegerValue instead.
TEST(Json, IntegersAreReadOnlyWhenTheyAreIntegersTheTypeHolds) {
  const nlohmann::json j = ParseJson(
      R"({"width": 640, "huge": 4.9e111, "half": 1.5, "text": "3", "big": 1099511627776, "negative": -1,
          "seed": 18446744073709551615, "list": [1, 2.5]})", "rig.json");
  EXPECT_EQ(IntegerAt(j, "width", "rig.json"), 640);
  EXPECT_EQ(IntegerAt<int64_t>(j, "big", "rig.json"), int64_t{1} << 40);
  EXPECT_EQ(IntegerAt<uint64_t>(j, "seed", "rig.json"), ~uint64_t{0});
  EXPECT_EQ(IntegerAt<int>(j, "negative", "rig.json"), -1);
  for (const char* key : {"huge", "half", "text", "big"}) {
    svbtdf::testing::ExpectError(ErrorKind::kFormat,
                                 "rig.json: has a '" + std::string(key) + "' that is not an integer of a sensible size",
                                 [&] { IntegerAt(j, key, "rig.json"); });
  }
  svbtdf::testing::ExpectError(ErrorKind::kFormat, "rig.json: has a 'negative'", [&] { IntegerAt<uint64_t>(j, "negative", "rig.json"); });
  svbtdf::testing::ExpectError(ErrorKind::kFormat, "rig.json: has a 'seed'", [&] { IntegerAt<int64_t>(j, "seed", "rig.json"); });
  svbtdf::testing::ExpectError(ErrorKind::kFormat, "rig.json: has a 'list' that is not an integer",
                               [&] { IntegerArrayAt<int>(j, "list", "rig.json"); });
  svbtdf::testing::ExpectError(ErrorKind::kFormat, "rig.json: has a 'width' that is not an array",
                               [&] { IntegerArrayAt<int>(j, "width", "rig.json"); });
}

}  // namespace
}  // namespace svbtdf::common
