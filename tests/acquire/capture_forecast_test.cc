// `svbtdf plan`'s forecast: images and disk as the capture loop and its free-space check count
// them, the duration's parts moving with what drives them, the dots' angles from the geometry,
// and the lobe widths from the dual-microfacet model against their small-angle closed form.
#include <gtest/gtest.h>

#include <cmath>

#include "svbtdf/acquire/capture_forecast.h"
#include "svbtdf/acquire/capture_session.h"
#include "svbtdf/common/error.h"

namespace svbtdf::acquire {
namespace {

constexpr double kDegree = 3.14159265358979323846 / 180.0;

class Forecast : public ::testing::Test {
 protected:
  CapturePlan plan_ = ScaleExposures(MakePlanPreset("tiny"), 0.01);
  simulate::RigFile rig_ = simulate::RigFileOfPreset("tiny");
  CaptureForecast Of(const CapturePlan& plan) { return ForecastCapture(plan, rig_, "tiny", {0.05, 0.2}); }
};

TEST_F(Forecast, ImagesAndDiskAreTheCaptureLoopsOwnCounts) {
  const CaptureForecast one = Of(plan_);
  EXPECT_EQ(one.images, static_cast<int64_t>(ExpandPlan(plan_).size()));
  const int64_t dot_images = static_cast<int64_t>(plan_.dots_px.size() * plan_.exposures_s.size());
  EXPECT_EQ(one.dot_images, dot_images);
  CapturePlan twice = plan_;
  twice.repeats = 2;
  const CaptureForecast two = Of(twice);
  EXPECT_EQ(two.images - one.images, dot_images);
  // Each extra dot image is one window-sized image (the plan's bytes_per_image) plus 5%.
  const double extra = static_cast<double>(two.bytes - one.bytes);
  EXPECT_NEAR(extra, dot_images * plan_.bytes_per_image * 1.05, 2.0 * dot_images);
  // Board views of a windowed camera are whole-sensor frames: they weigh more than a window's.
  CapturePlan more_boards = plan_;
  more_boards.board_views += 3;
  const double per_board = (Of(more_boards).bytes - one.bytes) / 3.0 / 1.05;
  EXPECT_NEAR(per_board, 1.0 * rig_.rig.window.sensor_width * rig_.rig.window.sensor_height * 3 * 2, 2.0);
}

TEST_F(Forecast, TheDurationsPartsMoveWithWhatDrivesThem) {
  const CaptureForecast base = Of(plan_);
  const CaptureDuration& d = base.duration;
  EXPECT_DOUBLE_EQ(d.total_s(), d.exposing_s + d.settling_s + d.control_s);
  // A pattern is shown once for all its brackets and repeats.
  EXPECT_DOUBLE_EQ(d.settling_s, d.patterns * plan_.settle_s);
  CapturePlan repeated = plan_;
  repeated.repeats = 3;
  const CaptureDuration r = Of(repeated).duration;
  double per_repeat = 0.0;
  for (double e : plan_.exposures_s) per_repeat += std::max(e, rig_.frame_time_s);
  EXPECT_NEAR(r.exposing_s - d.exposing_s, 2 * plan_.dots_px.size() * per_repeat, 1e-9);
  EXPECT_EQ(r.patterns, d.patterns);
  EXPECT_EQ(r.exposure_changes, d.exposure_changes);
  // Every exposure change costs the camera's control delay in frames.
  simulate::RigFile slow = rig_;
  slow.control_delay_frames = 2 * rig_.control_delay_frames;
  EXPECT_NEAR(ForecastCapture(plan_, slow, "slow", {}).duration.control_s, 2 * d.control_s, 1e-9);
  // Exposures shorter than a frame take a frame.
  const CaptureForecast fast = Of(ScaleExposures(plan_, 1e-6));
  EXPECT_NEAR(fast.duration.exposing_s, fast.images * rig_.frame_time_s, 1e-9);
}

// Camera 5 degrees from the normal: the dot nearest the straight-through direction lies almost
// straight below the sample's centre, and the dots' spacing there is the grid's pitch over the
// monitor's distance; the GGX lobe transmitted by a slab of index eta is, to first order, 2 x
// 0.6436 alpha (eta - 1) radians wide at half maximum (D halves where tan(theta_h) = 0.6436 alpha,
// and the slab turns the incident direction by (eta - 1) theta_h).
TEST_F(Forecast, AnglesFollowFromTheGeometryAndLobesFromTheModel) {
  rig_.rig.pose = simulate::RigConfig::PaperPose(2.0, 5.0 * kDegree);
  rig_.rig.dots.span_scale = 0.5;  // the rig's own grid must stay in view (the plan's dots need not)
  const CaptureForecast f = Of(plan_);
  ASSERT_EQ(f.coverage.size(), 5u);
  const DotCoverage& centre = f.coverage[0];
  const double pitch_px = std::hypot(plan_.dots_px[1].first - plan_.dots_px[0].first,
                                     plan_.dots_px[1].second - plan_.dots_px[0].second);
  const double pitch_deg = std::atan(pitch_px * rig_.rig.monitor.pixel_pitch / rig_.rig.monitor.distance) / kDegree;
  EXPECT_NEAR(centre.spacing_deg / pitch_deg, 1.0, 0.1);
  EXPECT_LT(centre.min_incidence_deg, centre.max_incidence_deg);
  EXPECT_LE(centre.straight_through_to_nearest_dot_deg, centre.spacing_deg);
  for (const LobeSampling& lobe : f.lobes) {
    const double expected_deg = 2 * 0.6436 * lobe.roughness * (f.eta - 1) / kDegree;
    EXPECT_NEAR(lobe.width_deg / expected_deg, 1.0, 0.1) << lobe.roughness;
    EXPECT_NEAR(lobe.dots_across, lobe.width_deg / centre.spacing_deg, 1e-9);
    EXPECT_EQ(lobe.verdict == "too sparse", lobe.dots_across < kMinDotsAcrossLobe);
  }
  EXPECT_GT(f.lobes[1].width_deg, 3 * f.lobes[0].width_deg);
  const std::string text = FormatForecast(f);
  EXPECT_NE(text.find("a GGX 0.05 lobe spans"), std::string::npos) << text;
}

TEST_F(Forecast, ADotOffTheRigsMonitorIsRefused) {
  plan_.dots_px[3] = {1e5, 10};
  try {
    Of(plan_);
    ADD_FAILURE() << "accepted";
  } catch (const common::Error& e) {
    EXPECT_NE(std::string(e.what()).find("dot 3"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace svbtdf::acquire
