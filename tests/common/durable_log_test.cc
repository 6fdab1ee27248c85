// The durable log: lines survive a crash at any byte of an append, and a torn tail never glues
// itself to the next line.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/durable_log.h"
#include "svbtdf/common/error.h"
#include "temp_folder.h"

namespace svbtdf::common {
namespace {
namespace fs = std::filesystem;

void WriteBytes(const fs::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

TEST(DurableLog, AnAbsentLogHasNoLinesAndIsCreatedByTheFirstAppend) {
  const testing::TempFolder folder;
  DurableLog log = DurableLog::Open(folder / "log.jsonl");
  EXPECT_TRUE(log.lines().empty());
  EXPECT_FALSE(fs::exists(folder / "log.jsonl"));
  log.Append(R"({"a":1})");
  log.Append(R"({"a":2})");
  EXPECT_EQ(ReadTextFile(folder / "log.jsonl"), "{\"a\":1}\n{\"a\":2}\n");
  EXPECT_EQ(DurableLog::Open(folder / "log.jsonl").lines(), (std::vector<std::string>{R"({"a":1})", R"({"a":2})"}));
}

TEST(DurableLog, KeepsEmptyLinesSoThatLineNumbersMatchTheFile) {
  const testing::TempFolder folder;
  WriteBytes(folder / "log", "one\n\nthree\n");
  EXPECT_EQ(DurableLog::Open(folder / "log").lines(), (std::vector<std::string>{"one", "", "three"}));
}

TEST(DurableLog, ATornTailIsLeftOutAndCutOffBeforeTheNextAppend) {
  const testing::TempFolder folder;
  WriteBytes(folder / "log", "{\"a\":1}\n{\"a\":");
  DurableLog log = DurableLog::Open(folder / "log", IsJsonObjectLine);
  EXPECT_EQ(log.lines(), std::vector<std::string>{"{\"a\":1}"});
  EXPECT_TRUE(log.had_torn_tail());
  log.Append("{\"a\":2}");
  EXPECT_EQ(ReadTextFile(folder / "log"), "{\"a\":1}\n{\"a\":2}\n");
}

TEST(DurableLog, AWholeLineThatLostItsNewlineIsKeptAndEnded) {
  const testing::TempFolder folder;
  WriteBytes(folder / "log", "{\"a\":1}\n{\"a\":2}");
  DurableLog log = DurableLog::Open(folder / "log", IsJsonObjectLine);
  EXPECT_EQ(log.lines(), (std::vector<std::string>{"{\"a\":1}", "{\"a\":2}"}));
  EXPECT_FALSE(log.had_torn_tail());
  log.Append("{\"a\":3}");
  EXPECT_EQ(ReadTextFile(folder / "log"), "{\"a\":1}\n{\"a\":2}\n{\"a\":3}\n");
}

TEST(DurableLog, WithoutAJudgeOfWholeLinesEveryUnterminatedTailIsTorn) {
  const testing::TempFolder folder;
  WriteBytes(folder / "log", "{\"a\":1}\n{\"a\":2}");
  DurableLog log = DurableLog::Open(folder / "log");
  EXPECT_EQ(log.lines(), std::vector<std::string>{"{\"a\":1}"});
  log.Append("x");
  EXPECT_EQ(ReadTextFile(folder / "log"), "{\"a\":1}\nx\n");
}

// A crash can stop an append after any of its bytes. Whatever the byte, reopening and appending
// gives the lines before the cut, the cut line if it was whole, and the new line: never a glued
// or lost line.
TEST(DurableLog, SurvivesACutAtEveryByteOfTheFile) {
  const testing::TempFolder folder;
  const std::vector<std::string> lines = {R"({"key":"dot/q0000/e0/r0","bytes":12})", R"({"key":"dot/q0001/e0/r0"})",
                                          R"([1,2,3])"};
  std::string full;
  for (const std::string& line : lines) full += line + "\n";
  for (size_t cut = 0; cut <= full.size(); ++cut) {
    const fs::path path = folder / ("log" + std::to_string(cut));
    WriteBytes(path, full.substr(0, cut));
    DurableLog::Open(path, IsJsonObjectLine).Append(R"({"new":true})");
    const std::vector<std::string> reread = DurableLog::Open(path, IsJsonObjectLine).lines();
    ASSERT_FALSE(reread.empty()) << cut;
    EXPECT_EQ(reread.back(), R"({"new":true})") << cut;
    for (size_t n = 0; n + 1 < reread.size(); ++n) EXPECT_EQ(reread[n], lines.at(n)) << "cut at byte " << cut;
    // Every line whose newline was written survives.
    const size_t complete = std::count(full.begin(), full.begin() + cut, '\n');
    EXPECT_GE(reread.size() - 1, complete) << cut;
  }
}

TEST(DurableLog, RefusesALineWithANewline) {
  const testing::TempFolder folder;
  DurableLog log = DurableLog::Open(folder / "log");
  EXPECT_THROW(log.Append("two\nlines"), Error);
}

TEST(DurableLog, AnUnwritableLogNamesItsFile) {
  const testing::TempFolder folder;
  DurableLog log = DurableLog::Open(folder / "missing-folder" / "log");
  try {
    log.Append("x");
    FAIL() << "appended into a folder that does not exist";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("missing-folder/log"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace svbtdf::common
