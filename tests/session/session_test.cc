// The capture session format: durability, verification and robustness against broken files.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/durable_log.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/fault_injection.h"
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

  // Replaces a journalled image's file with `bytes` and journals them as they are (size and CRC),
  // as a tool that edits sessions behind svbtdf's back, or an older svbtdf on a full disk, would.
  void ReplaceJournalled(const std::string& key, const std::string& bytes) const {
    const fs::path file = folder_ / session::Session::FileForKey(key);
    common::WriteTextAtomically(file, bytes);
    std::string journal;
    const common::DurableLog log = common::DurableLog::Open(folder_ / "journal.jsonl");
    for (const std::string& line : log.lines()) {
      nlohmann::json entry = nlohmann::json::parse(line);
      if (entry["key"] == key) {
        entry["bytes"] = bytes.size();
        entry["crc32"] = session::FileCrc32(file);
      }
      journal += entry.dump() + "\n";
    }
    common::WriteTextAtomically(folder_ / "journal.jsonl", journal);
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

// A full disk at any write of a capture (the image's write, fsync, rename, the journal's append)
// leaves the key uncaptured: never a journal line for an image that is not whole on disk.
TEST_F(SessionTest, AFullDiskNeverJournalsABrokenImage) {
  session::Session session = session::Session::Create(folder_, rig_, plan_);
  for (int step = 1; step <= 6; ++step) {
    common::InjectFaultForTesting(step, common::FaultAction::kFail);
    EXPECT_THROW(session.AddImage("dark/e0", Frame(3), 0.1, 1.0), common::Error) << "step " << step;
    common::InjectFaultForTesting(0, common::FaultAction::kProceed);
    const session::Session reopened = session::Session::Open(folder_);
    if (reopened.Contains("dark/e0")) {  // the failure came after the journal line was on disk
      EXPECT_TRUE(reopened.Verify(true, true).corrupt.empty()) << "step " << step;
      break;
    }
    session = session::Session::Open(folder_);
  }
  session = session::Session::Open(folder_);
  if (!session.Contains("dark/e0")) session.AddImage("dark/e0", Frame(3), 0.1, 1.0);
  EXPECT_EQ(session.ReadImage("dark/e0", true).pixels, Frame(3).pixels);
}

// A file that matches its journal line's size and CRC but does not decode (journalled damaged by
// an older svbtdf, or replaced by a tool) passes the checksum check; --decode finds it.
TEST_F(SessionTest, VerifyDecodeFindsImagesJournalledWithTheirDamage) {
  session::Session session = session::Session::Create(folder_, rig_, plan_);
  for (const std::string& key : plan_) session.AddImage(key, Frame(7), 0.1, 1.0);
  const fs::path image = folder_ / session::Session::FileForKey("board/v00");
  const std::string bytes = common::ReadTextFile(image);
  ReplaceJournalled("board/v00", bytes.substr(0, bytes.size() / 2));  // cut short, as a full disk did
  const session::Session reopened = session::Session::Open(folder_);
  EXPECT_TRUE(reopened.Verify(/*check_crc=*/true).complete());
  const session::SessionVerification decoded = reopened.Verify(/*check_crc=*/true, /*decode=*/true);
  EXPECT_EQ(decoded.corrupt, std::vector<std::string>{"board/v00"});
  EXPECT_FALSE(decoded.complete());
}

// A plan that lost keys makes their journal lines unexpected: not a complete session.
TEST_F(SessionTest, JournalledKeysThePlanLostMakeTheSessionIncomplete) {
  session::Session session = session::Session::Create(folder_, rig_, plan_);
  for (const std::string& key : plan_) session.AddImage(key, Frame(7), 0.1, 1.0);
  { std::ofstream(folder_ / "plan.json", std::ios::trunc) << R"({"captures": []})"; }
  const session::SessionVerification report = session::Session::Open(folder_).Verify();
  EXPECT_EQ(report.unexpected.size(), plan_.size());
  EXPECT_FALSE(report.complete());
}

// A kill while a session is being created leaves no half-made session folder.
TEST_F(SessionTest, ACreationThatFailsLeavesNoSessionFolder) {
  common::InjectFaultForTesting(2, common::FaultAction::kFail);  // the plan's fsync
  EXPECT_THROW(session::Session::Create(folder_, rig_, plan_), common::Error);
  common::InjectFaultForTesting(0, common::FaultAction::kProceed);
  EXPECT_FALSE(fs::exists(folder_));
  EXPECT_TRUE(fs::is_empty(root_.path()));
  session::Session::Create(folder_, rig_, plan_);  // the rerun succeeds
  EXPECT_EQ(session::Session::Open(folder_).planned_keys(), plan_);
}

// Images that are not what the rig's camera takes are refused by name, not processed.
TEST_F(SessionTest, ImagesUnlikeTheRigsCameraAreRefusedNamingTheFile) {
  const nlohmann::json rig = {{"camera", {{"model", "test"}, {"width", 8}, {"height", 4}, {"channels", 1}, {"bit_depth", 12}}}};
  session::Session session = session::Session::Create(folder_, rig, plan_);
  common::CameraImage colour = Frame(100);
  colour.channels = 3;
  colour.pixels.assign(8 * 4 * 3, 100);
  common::CameraImage wider = Frame(100);
  wider.width = 16;
  wider.pixels.assign(16 * 4, 100);
  common::CameraImage good = Frame(100);
  good.bits_per_sample = 12;
  session.AddImage("dark/e0", good, 0.1, 1.0);
  session.AddImage("board/v00", colour, 0.1, 1.0);
  session.AddImage("dot/q0000/e0/r0", wider, 0.1, 1.0);
  session.AddImage("dot/q0001/e0/r0", good, 0.1, 1.0);
  // An 8-bit PNG (of the right size) in place of the dark frame.
  const fs::path eight_bit = root_ / "eight_bit.png";
  common::WriteRgb8Png(eight_bit, std::vector<uint8_t>(8 * 4 * 3, 9), 8, 4);
  ReplaceJournalled("dark/e0", common::ReadTextFile(eight_bit));
  session = session::Session::Open(folder_);
  const std::vector<std::pair<std::string, std::string>> refusals = {
      {"dark/e0", "an 8-bit image"}, {"board/v00", "a 3-channel image"}, {"dot/q0000/e0/r0", "16x4 pixels"}};
  for (const auto& [key, words] : refusals) {
    try {
      session.ReadImage(key);
      ADD_FAILURE() << key << " was read";
    } catch (const common::Error& e) {
      EXPECT_EQ(e.kind(), common::ErrorKind::kFormat);
      EXPECT_NE(std::string(e.what()).find(session::Session::FileForKey(key)), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(session.ReadImage("dot/q0001/e0/r0").width, 8);
}

}  // namespace
}  // namespace svbtdf
