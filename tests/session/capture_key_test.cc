// The capture-key grammar of docs/session-format.md: one spelling per key, and the one capture
// order of the house.
#include <gtest/gtest.h>

#include <random>
#include <set>
#include <string>

#include "svbtdf/session/capture_key.h"

namespace svbtdf::session {
namespace {

TEST(CaptureKey, FormatsEveryKindAsTheSessionFormatSpellsIt) {
  EXPECT_EQ(CaptureKey::Dark(1, 2).Format(), "dark/e1/r2");
  EXPECT_EQ(CaptureKey::BoardView(3).Format(), "board/v03");
  EXPECT_EQ(CaptureKey::SamplePlaneView(0).Format(), "sample_plane/v00");
  EXPECT_EQ((CaptureKey{CaptureKind::kMonitorPoseView, 0, 0, 0, 7}).Format(), "monitor_pose/v07");
  EXPECT_EQ(CaptureKey::AllDots().Format(), "all_dots/e0");
  EXPECT_EQ(CaptureKey::Fiducials().Format(), "fiducials/e0");
  EXPECT_EQ(CaptureKey::FlatWhite(2).Format(), "flat_white/e2");
  EXPECT_EQ(CaptureKey::Dot(12, 1, 0).Format(), "dot/q0012/e1/r0");
  EXPECT_EQ(CaptureKey::Dot(123456, 0, 3).Format(), "dot/q123456/e0/r3");
  EXPECT_EQ(CaptureKey::BoardView(150).Format(), "board/v150");
}

TEST(CaptureKey, ParseInvertsFormat) {
  const std::vector<CaptureKey> keys = {
      CaptureKey::Dark(0, 0),        CaptureKey::Dark(3, 11),  CaptureKey::BoardView(0), CaptureKey::BoardView(123),
      CaptureKey::SamplePlaneView(4), CaptureKey::AllDots(),   CaptureKey::Fiducials(1), CaptureKey::FlatWhite(),
      CaptureKey::Dot(0, 0, 0),       CaptureKey::Dot(9999, 2, 1), CaptureKey::Dot(10000, 0, 0)};
  for (const CaptureKey& key : keys) {
    const std::optional<CaptureKey> parsed = CaptureKey::Parse(key.Format());
    ASSERT_TRUE(parsed) << key.Format();
    EXPECT_EQ(*parsed, key) << key.Format();
  }
}

TEST(CaptureKey, RefusesEverythingButTheOneSpelling) {
  for (const char* text : {"", "dot", "dot/", "dot/q0012/e1", "dot/q12/e1/r0", "dot/q0012/e01/r0", "dot/q0012/e1/r0/",
                           "dot/q-012/e1/r0", "dot/q0012/e1/r+0", "board/v5", "board/v005", "board/05", "dark/e0",
                           "dark/e0/n0", "all_dots", "all_dots/e", "all_dots/0", "flat/e0", "Dot/q0012/e1/r0",
                           "dot/q0012/e1/r99999999999", "dot//q0012/e1/r0", "images/dot/q0012/e1/r0"}) {
    EXPECT_FALSE(CaptureKey::Parse(text)) << text;
  }
}

// Whatever the bytes, Parse returns, and what it accepts formats back to the same bytes. The
// trial strings are valid keys with a few random edits, so that they reach the accepting paths.
TEST(CaptureKey, ArbitraryTextNeverParsesToAnotherSpelling) {
  std::mt19937 rng(7);
  const std::vector<std::string> seeds = {"dot/q0012/e1/r0", "dark/e0/r1", "board/v03", "sample_plane/v00",
                                          "all_dots/e0", "fiducials/e0", "flat_white/e0", "monitor_pose/v01"};
  const std::string alphabet = "dotq0123456789/ervbaslpi_fxwhkmn-+ ";
  int accepted = 0, edited_and_accepted = 0;
  for (int trial = 0; trial < 200000; ++trial) {
    std::string text = seeds[rng() % seeds.size()];
    const int edits = std::uniform_int_distribution<int>(0, 3)(rng);
    for (int k = 0; k < edits; ++k) {
      const size_t at = rng() % (text.size() + 1);
      const char c = alphabet[rng() % alphabet.size()];
      switch (rng() % 3) {
        case 0: text.insert(text.begin() + at, c); break;
        case 1: if (at < text.size()) text.erase(at, 1); break;
        default: if (at < text.size()) text[at] = c; break;
      }
    }
    const std::optional<CaptureKey> parsed = CaptureKey::Parse(text);
    if (parsed) {
      ++accepted;
      if (edits > 0) ++edited_and_accepted;
      EXPECT_EQ(parsed->Format(), text);
    }
  }
  EXPECT_GT(edited_and_accepted, 100);  // edits that keep a key valid (a digit changed) are tried
  EXPECT_LT(accepted, 200000);
}

TEST(CaptureOrder, CalibrationCapturesComeFirstThenEveryDotAtEveryBracket) {
  CaptureCounts counts;
  counts.brackets = 2;
  counts.dark_frames = 2;
  counts.board_views = 3;
  counts.sample_plane_views = 1;
  counts.all_dots = counts.fiducials = counts.flat_white = true;
  counts.dots = 4;
  counts.repeats = 2;
  const std::vector<CaptureKey> order = CaptureOrder(counts);
  ASSERT_EQ(order.size(), 2u * 2 + 3 + 1 + 3 + 4u * 2 * 2);
  std::vector<std::string> keys;
  for (const CaptureKey& key : order) keys.push_back(key.Format());
  EXPECT_EQ(keys[0], "dark/e0/r0");
  EXPECT_EQ(keys[3], "dark/e1/r1");
  EXPECT_EQ(keys[4], "board/v00");
  EXPECT_EQ(keys[7], "sample_plane/v00");
  EXPECT_EQ(keys[8], "all_dots/e0");
  EXPECT_EQ(keys[9], "fiducials/e0");
  EXPECT_EQ(keys[10], "flat_white/e0");
  EXPECT_EQ(keys[11], "dot/q0000/e0/r0");
  EXPECT_EQ(keys[12], "dot/q0000/e0/r1");
  EXPECT_EQ(keys[13], "dot/q0000/e1/r0");
  EXPECT_EQ(keys.back(), "dot/q0003/e1/r1");
  EXPECT_EQ(std::set<std::string>(keys.begin(), keys.end()).size(), keys.size());  // no key twice
}

TEST(CaptureOrder, LeavesOutWhatIsNotPlanned) {
  CaptureCounts counts;
  counts.dots = 2;
  const std::vector<CaptureKey> order = CaptureOrder(counts);
  ASSERT_EQ(order.size(), 2u);
  EXPECT_EQ(order[1], CaptureKey::Dot(1, 0, 0));
}

}  // namespace
}  // namespace svbtdf::session
