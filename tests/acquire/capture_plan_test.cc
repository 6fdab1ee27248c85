// The capture plan of `svbtdf acquire`: the tiny preset describes the simulator's captures, plan
// files in both unit systems parse to the same resolved plan, and bad or garbled files are always
// a svbtdf::Error naming the file, never a crash.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <string>

#include "svbtdf/acquire/capture_plan.h"
#include "svbtdf/common/error.h"
#include "svbtdf/session/fiducials.h"
#include "svbtdf/simulate/capture_render.h"
#include "svbtdf/simulate/truth_io.h"

namespace svbtdf::acquire {
namespace {

const char* kGridPlan = R"({
  "format": "svbtdf-capture-plan", "version": 1, "name": "film",
  "monitor": {"pixel_pitch_mm": 0.25},
  "dots": {"cols": 3, "rows": 2, "units": "mm", "pitch": [10, 5], "origin": [20, 30], "radius": 1},
  "exposures_s": [0.01, 0.16], "repeats": 2, "settle_s": 0.3, "dark_frames": 1,
  "calibration": {"board_views": 4, "board_exposure_s": 0.02, "sample_plane_views": 1,
                  "all_dots_exposure_s": 0.005, "flat_white_exposure_s": 0.005},
  "rig": {"monitor_distance_mm": 40, "board": "chessboard:9x6:25", "sample_width_mm": 80, "emission": "lcd"}
})";

TEST(CapturePlan, TinyPresetDescribesTheSimulatorsCaptures) {
  const CapturePlan plan = MakePlanPreset("tiny");
  const std::unique_ptr<simulate::SimulatedSetup> setup = simulate::MakeSimulatedSetup(simulate::MakePreset("tiny"), 1, 0);
  // The exposures and scenes the simulated lab planned, so that `svbtdf simulate` (this plan on the
  // simulated rig) exposes every image as the simulator meant.
  EXPECT_EQ(plan.exposures_s, setup->plan.dot_exposures_s);
  EXPECT_EQ(plan.board_exposure_s, setup->plan.board_exposure_s);
  EXPECT_EQ(plan.all_dots_exposure_s, setup->plan.all_dots_exposure_s);
  EXPECT_EQ(plan.flat_white_exposure_s, setup->plan.flat_exposure_s);
  EXPECT_EQ(plan.board_views, static_cast<int>(setup->plan.zhang_boards.size()));
  EXPECT_EQ(plan.dark_frames, setup->rig->config().dark_frames);
  const std::vector<PlannedCapture> planned = ExpandPlan(plan);
  const size_t brackets = plan.exposures_s.size(), dots = setup->rig->dots().size();
  // darks (per bracket), boards, holder, all-dots, fiducials, flat, one image per dot and bracket
  EXPECT_EQ(planned.size(), plan.dark_frames * brackets + plan.board_views + 4 + dots * brackets);
  ASSERT_EQ(plan.dots_px.size(), setup->rig->dots().size());
  for (size_t q = 0; q < plan.dots_px.size(); ++q) {
    EXPECT_EQ(plan.dots_px[q].first, setup->rig->dots()[q].monitor_x);
    EXPECT_EQ(plan.dots_px[q].second, setup->rig->dots()[q].monitor_y);
  }
  EXPECT_EQ(plan.dot_radius_px, setup->rig->config().dots.radius_px);
}

TEST(CapturePlan, GridsInMillimetresResolveToMonitorPixelsAndRoundTrip) {
  const CapturePlan plan = ParseCapturePlan(kGridPlan, "film.json");
  ASSERT_EQ(plan.dots_px.size(), 6u);
  EXPECT_DOUBLE_EQ(plan.dots_px[0].first, 80.0);   // 20 mm / 0.25 mm
  EXPECT_DOUBLE_EQ(plan.dots_px[5].first, 160.0);  // (20 + 2 * 10) mm
  EXPECT_DOUBLE_EQ(plan.dots_px[5].second, 140.0); // (30 + 5) mm
  EXPECT_DOUBLE_EQ(plan.dot_radius_px, 4.0);
  EXPECT_EQ(plan.rig.monitor_distance_mm, 40.0);
  EXPECT_EQ(plan.rig.board, "chessboard:9x6:25");
  const std::vector<PlannedCapture> captures = ExpandPlan(plan);
  // 2 x 1 dark, 4 boards, 1 sample plane, all dots, fiducials, flat, 6 dots x 2 brackets x 2 repeats.
  EXPECT_EQ(captures.size(), 2u + 4 + 1 + 1 + 1 + 1 + 24);
  // The fiducial dots, lit at once at the all-dots exposure, right after all the dots.
  const auto fiducials = std::find_if(captures.begin(), captures.end(),
                                      [](const PlannedCapture& c) { return c.key == "fiducials/e0"; });
  ASSERT_NE(fiducials, captures.end());
  EXPECT_EQ((fiducials - 1)->key, "all_dots/e0");
  EXPECT_EQ(fiducials->pattern.kind, Pattern::Kind::kAllDots);
  EXPECT_EQ(fiducials->exposure_s, plan.all_dots_exposure_s);
  ASSERT_EQ(plan.fiducial_dots, session::FiducialDots(3, 2));
  ASSERT_EQ(fiducials->pattern.all_dots_px.size(), plan.fiducial_dots.size());
  for (size_t k = 0; k < plan.fiducial_dots.size(); ++k) {
    EXPECT_EQ(fiducials->pattern.all_dots_px[k], plan.dots_px[plan.fiducial_dots[k]]);
  }
  EXPECT_EQ(captures.front().key, "dark/e0/r0");
  EXPECT_EQ(captures.back().key, "dot/q0005/e1/r1");
  EXPECT_EQ(captures.back().pattern.x_px, 160.0);
  // The resolved form parses to the very same plan: what resuming compares.
  const nlohmann::json resolved = CapturePlanToJson(plan);
  EXPECT_EQ(CapturePlanToJson(ParseCapturePlan(resolved.dump(), "resolved")), resolved);
}

// Each bad plan is an Error of kind format naming the file and, where there is one, the field.
TEST(CapturePlan, BadPlansAreClearErrorsNamingTheFileAndField) {
  const std::string good = kGridPlan;
  const auto edit = [&](const std::string& from, const std::string& to) {
    const size_t at = good.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at == std::string::npos) return good;
    return good.substr(0, at) + to + good.substr(at + from.size());
  };
  const std::vector<std::pair<std::string, std::string>> cases = {
      {edit("\"version\": 1", "\"version\": 2"), "version 2"},
      {edit("\"exposures_s\": [0.01, 0.16]", "\"exposures_s\": [0.01, -1]"), "exposures_s"},
      {edit("\"exposures_s\"", "\"exposure_s\""), "exposure_s"},
      {edit("\"monitor\": {\"pixel_pitch_mm\": 0.25},", ""), "dots.units"},
      {edit("\"cols\": 3", "\"cols\": \"3\""), "dots.cols"},
      {edit("\"board_views\": 4", "\"board_views\": 2"), "calibration.board_views"},
      {edit("\"repeats\": 2", "\"repeats\": 1e9"), "repeats"},
      {edit("\"lcd\"", "\"crt\""), "rig.emission"},
      {"[]", "the plan"},
      {"", "not valid JSON"},
  };
  for (const auto& [text, field] : cases) {
    try {
      ParseCapturePlan(text, "bad-plan.json");
      ADD_FAILURE() << "accepted: " << text;
    } catch (const common::Error& e) {
      EXPECT_EQ(e.kind(), common::ErrorKind::kFormat) << e.what();
      EXPECT_NE(std::string(e.what()).find("bad-plan.json"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(ReadCapturePlan("/nonexistent/plan.json"), common::Error);
}

// Truncations at every byte and thousands of deterministic byte mutations: each either parses to
// a plan that expands, or is a svbtdf::Error naming the file. Anything else fails the test.
TEST(CapturePlan, GarbledPlansNeverCrashAndAlwaysThrowSvbtdfErrors) {
  const std::string good = kGridPlan;
  uint64_t state = 0x9e3779b97f4a7c15ULL;
  const auto next = [&] {
    state ^= state << 13, state ^= state >> 7, state ^= state << 17;
    return state;
  };
  const char kBytes[] = "{}[]\":,0123456789-+eE.truefalsnul \n\\\x80\xff";
  int parsed = 0, refused = 0;
  const auto attempt = [&](const std::string& text) {
    try {
      const CapturePlan plan = ParseCapturePlan(text, "garbled.json");
      EXPECT_EQ(ExpandPlan(plan).size() > 0, true);
      ++parsed;
    } catch (const common::Error& e) {
      EXPECT_NE(std::string(e.what()).find("garbled.json"), std::string::npos) << e.what();
      ++refused;
    } catch (const std::exception& e) {
      ADD_FAILURE() << "not a svbtdf::Error: " << e.what() << "\n" << text;
    }
  };
  for (size_t n = 0; n < good.size(); ++n) attempt(good.substr(0, n));
  for (int trial = 0; trial < 3000; ++trial) {
    std::string text = good;
    const int edits = 1 + static_cast<int>(next() % 4);
    for (int k = 0; k < edits; ++k) {
      const size_t at = next() % text.size();
      switch (next() % 3) {
        case 0: text[at] = kBytes[next() % (sizeof kBytes - 1)]; break;
        case 1: text.erase(at, 1 + next() % 8); break;
        default: text = text.substr(0, at) + kBytes[next() % (sizeof kBytes - 1)] + text.substr(at); break;
      }
      if (text.empty()) text.push_back('{');
    }
    attempt(text);
  }
  EXPECT_GT(refused, 3000);
  EXPECT_GT(parsed, 0);  // some mutations are harmless (whitespace, digits)
}

}  // namespace
}  // namespace svbtdf::acquire
