// Reading user-supplied JSON (common/json.h): one message naming the file for every kind of bad
// text, and nesting bounded before anything recursive can touch the value.
#include <gtest/gtest.h>

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

}  // namespace
}  // namespace svbtdf::common
