// The capture session format: durability, verification and robustness against broken files.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/session/session.h"
#include "temp_folder.h"

namespace svbtdf {
namespace {
namespace fs = std::filesystem;

class SessionTest : public ::testing::Test {
 protected:
  static common::CameraImage Frame(uint16_t value) {
    common::CameraImage image;
    image.width = 8;
    image.height = 4;
    image.pixels.assign(32, value);
    return image;
  }

  svbtdf::testing::TempFolder root_;
  const fs::path folder_ = root_ / "session";  // not there yet: Session::Create makes it
  const std::vector<std::string> plan_ = {"dark/e0", "board/v00", "dot/q0000/e0/r0", "dot/q0001/e0/r0"};
  const nlohmann::json rig_ = {{"camera", {{"model", "test"}}}};
};

TEST_F(SessionTest, ImagesAreJournalledAndSurviveReopening) {
  session::Session session = session::Session::Create(folder_, rig_, plan_);
  session.AddImage("dark/e0", Frame(3), 0.1, 1.0);
  session.AddImage("board/v00", Frame(400), 0.01, 2.0);
  EXPECT_FALSE(session.Verify().complete());
  EXPECT_EQ(session.Verify().missing.size(), 2u);

  session::Session reopened = session::Session::Open(folder_);
  EXPECT_TRUE(reopened.Contains("board/v00"));
  EXPECT_EQ(reopened.Entry("board/v00").gain, 2.0);
  EXPECT_EQ(reopened.ReadImage("board/v00", /*check_crc=*/true).pixels, Frame(400).pixels);
  EXPECT_EQ(reopened.rig().camera.model, "test");
  reopened.AddImage("dot/q0000/e0/r0", Frame(10), 1.0, 1.0);
  reopened.AddImage("dot/q0001/e0/r0", Frame(11), 1.0, 1.0);
  EXPECT_TRUE(reopened.Verify().complete()) << reopened.Verify().Summary();
  EXPECT_EQ(reopened.Verify().Summary(), "complete and intact");
}

TEST_F(SessionTest, NothingIsOverwritten) {
  session::Session session = session::Session::Create(folder_, rig_, plan_);
  session.AddImage("dark/e0", Frame(3), 0.1, 1.0);
  EXPECT_THROW(session.AddImage("dark/e0", Frame(4), 0.1, 1.0), common::Error);
  EXPECT_THROW(session::Session::Create(folder_, rig_, plan_), common::Error);  // the folder is not empty
  EXPECT_THROW(session.AddImage("dot/q9999/e0/r0", Frame(1), 1.0, 1.0), common::Error);  // not planned
  EXPECT_EQ(session::Session::Open(folder_).ReadImage("dark/e0").pixels, Frame(3).pixels);
}

TEST_F(SessionTest, VerifyFindsCorruptAndMissingFiles) {
  session::Session session = session::Session::Create(folder_, rig_, plan_);
  for (const std::string& key : plan_) session.AddImage(key, Frame(7), 1.0, 1.0);
  // Flip one byte of one image (same size): only the CRC can tell.
  const fs::path file = folder_ / session::Session::FileForKey("board/v00");
  std::string bytes = common::ReadTextFile(file);
  bytes[bytes.size() / 2] ^= 0x5a;
  std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes;
  fs::remove(folder_ / session::Session::FileForKey("dark/e0"));
  const session::SessionVerification report = session::Session::Open(folder_).Verify();
  EXPECT_FALSE(report.complete());
  EXPECT_EQ(report.corrupt, (std::vector<std::string>{"dark/e0", "board/v00"}));
  EXPECT_THROW(session::Session::Open(folder_).ReadImage("board/v00", true), common::Error);
}

TEST_F(SessionTest, ACrashMidAppendLeavesAReadableJournal) {
  session::Session session = session::Session::Create(folder_, rig_, plan_);
  session.AddImage("dark/e0", Frame(3), 0.1, 1.0);
  std::ofstream(folder_ / "journal.jsonl", std::ios::app) << R"({"key": "board/v00", "fi)";  // cut short
  session::Session reopened = session::Session::Open(folder_);
  EXPECT_EQ(reopened.entries().size(), 1u);
  EXPECT_FALSE(reopened.Contains("board/v00"));
}

// Resuming after a torn append: the fragment must not swallow the next journal line.
TEST_F(SessionTest, AppendingAfterACrashMidAppendKeepsTheJournalReadable) {
  {
    session::Session session = session::Session::Create(folder_, rig_, plan_);
    session.AddImage("dark/e0", Frame(3), 0.1, 1.0);
  }
  std::ofstream(folder_ / "journal.jsonl", std::ios::app) << R"({"key": "board/v00", "fi)";  // cut short
  {
    session::Session resumed = session::Session::Open(folder_);
    resumed.AddImage("board/v00", Frame(4), 0.1, 1.0);
  }
  // A complete last line that lost its newline is kept, and the next one starts a new line.
  std::string text = common::ReadTextFile(folder_ / "journal.jsonl");
  ASSERT_EQ(text.back(), '\n');
  text.pop_back();
  common::WriteTextAtomically(folder_ / "journal.jsonl", text);
  {
    session::Session resumed = session::Session::Open(folder_);
    EXPECT_EQ(resumed.entries().size(), 2u);
    resumed.AddImage("dot/q0000/e0/r0", Frame(5), 0.1, 1.0);
  }
  const session::Session reopened = session::Session::Open(folder_);
  EXPECT_EQ(reopened.entries().size(), 3u);
  EXPECT_TRUE(reopened.Contains("board/v00"));
  EXPECT_TRUE(reopened.Contains("dot/q0000/e0/r0"));
  const session::SessionVerification report = reopened.Verify();
  EXPECT_TRUE(report.corrupt.empty() && report.duplicated.empty()) << report.Summary();
  EXPECT_EQ(report.missing, std::vector<std::string>{"dot/q0001/e0/r0"});
}

TEST_F(SessionTest, BrokenJournalLinesAreErrorsNamingFileAndLine) {
  session::Session session = session::Session::Create(folder_, rig_, plan_);
  session.AddImage("dark/e0", Frame(3), 0.1, 1.0);
  std::ofstream(folder_ / "journal.jsonl", std::ios::app) << "garbage\n" << R"({"key":"x"})" << "\n";
  try {
    session::Session::Open(folder_);
    FAIL();
  } catch (const common::Error& e) {
    EXPECT_NE(std::string(e.what()).find("journal.jsonl:2"), std::string::npos) << e.what();
  }
}

// Issue 15: 150,000 nested [] in session.json, plan.json or a journal line crashed every command
// that opened the session; each is now the file's one-line format error.
TEST_F(SessionTest, DeeplyNestedJsonIsAFormatErrorNamingTheFile) {
  session::Session session = session::Session::Create(folder_, rig_, plan_);
  session.AddImage("dark/e0", Frame(3), 0.1, 1.0);
  const std::string deep = std::string(150000, '[') + std::string(150000, ']');
  for (const char* name : {"session.json", "plan.json"}) {
    const fs::path path = folder_ / name;
    const std::string original = common::ReadTextFile(path);
    common::WriteTextAtomically(path, "{\"rig\": " + deep + "}");
    try {
      session::Session::Open(folder_);
      FAIL() << name;
    } catch (const common::Error& e) {
      EXPECT_EQ(e.kind(), common::ErrorKind::kFormat);
      EXPECT_NE(std::string(e.what()).find(path.string() + ": is not valid JSON: nested deeper"), std::string::npos) << e.what();
    }
    common::WriteTextAtomically(path, original);
  }
  std::ofstream(folder_ / "journal.jsonl", std::ios::app) << "{\"key\": " << deep << "}\n" << R"({"key":"x"})" << "\n";
  try {
    session::Session::Open(folder_);
    FAIL() << "journal";
  } catch (const common::Error& e) {
    EXPECT_NE(std::string(e.what()).find("journal.jsonl:2: is not a valid journal line"), std::string::npos) << e.what();
  }
}

TEST_F(SessionTest, RandomlyDamagedFilesNeverCrashTheReader) {
  // A small fuzz: truncate or scramble the manifest, plan and journal in many ways; Open must
  // either succeed or throw svbtdf::Error, never crash or throw anything else.
  session::Session session = session::Session::Create(folder_, rig_, plan_);
  for (const std::string& key : plan_) session.AddImage(key, Frame(5), 1.0, 1.0);
  std::mt19937_64 rng(1);
  for (const char* name : {"session.json", "plan.json", "journal.jsonl"}) {
    const fs::path path = folder_ / name;
    const std::string original = common::ReadTextFile(path);
    for (int trial = 0; trial < 200; ++trial) {
      std::string damaged = original;
      const int mode = trial % 3;
      if (mode == 0) damaged.resize(rng() % (damaged.size() + 1));
      if (mode == 1) damaged[rng() % damaged.size()] = static_cast<char>(rng() % 256);
      if (mode == 2) damaged.insert(rng() % damaged.size(), std::string(1 + rng() % 5, "{}[]\",:0e9-x\n"[rng() % 13]));
      common::WriteTextAtomically(path, damaged);
      try {
        session::Session::Open(folder_).Verify();
      } catch (const common::Error&) {
      } catch (const std::exception& e) {
        FAIL() << name << " trial " << trial << ": " << e.what();
      }
    }
    common::WriteTextAtomically(path, original);
  }
}

}  // namespace
}  // namespace svbtdf
