// Tests of the synthetic captures: planned exposures, chessboard images that OpenCV finds at the true corners, and the rig truth file.

#include <gtest/gtest.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <filesystem>

#include "svbtdf/common/error.h"
#include "svbtdf/common/interrupt.h"
#include "svbtdf/simulate/capture_render.h"
#include "svbtdf/simulate/truth_io.h"
#include "svbtdf/simulate/truth_material.h"
#include "temp_folder.h"

namespace svbtdf::simulate {
namespace {

struct TinyCapture {
  SimulationPreset preset = MakePreset("tiny");
  Rig rig{preset.rig};
  TruthMaterial material = TruthMaterial::FromPattern(preset.pattern, 32, 32, preset.eta, 5);
  RigRenderer renderer{rig, &material, 2};
  CaptureTruth plan = PlanCapture(preset, renderer, 5);
};

TEST(Capture, BrightestDotImageIsExposedAsPlanned) {
  TinyCapture tiny;
  // The probe dot's shortest exposure peaks at peak_fill of the well (noise aside).
  const double peak = tiny.renderer.ProbePeakRadiance();
  const double electrons = tiny.renderer.MeanElectrons(peak, model::Vec2(tiny.rig.config().intrinsics.cx,
                                                                  tiny.rig.config().intrinsics.cy),
                                                       tiny.plan.dot_exposures_s[0]);
  EXPECT_NEAR(electrons / tiny.rig.config().sensor.full_well, tiny.preset.peak_fill, 1e-9);
  EXPECT_NEAR(tiny.plan.dot_exposures_s[1] / tiny.plan.dot_exposures_s[0], 16.0, 1e-12);
}

// OpenCV finds every rendered chessboard, and its corners lie on the true projections.
TEST(Capture, BoardImagesAreFoundAtTheTrueCorners) {
  TinyCapture tiny;
  std::vector<BoardPose> poses = tiny.plan.zhang_boards;
  poses.push_back(tiny.plan.holder_board);
  double worst = 0.0;
  for (const BoardPose& pose : poses) {
    // The Zhang views are whole-sensor images of the big board, the holder view the window.
    const bool holder = &pose == &poses.back();
    const BoardConfig& b = holder ? tiny.rig.config().holder_board : tiny.rig.config().board;
    const PinholeCamera& camera = holder ? tiny.rig.camera() : tiny.rig.sensor_camera();
    const CaptureId id{holder ? session::CaptureKey::SamplePlaneView(0) : session::CaptureKey::BoardView(0),
                       tiny.plan.board_exposure_s};
    common::FloatImage radiance;
    if (holder) {
      tiny.renderer.RenderHolderBoard(pose, &radiance);
    } else {
      tiny.renderer.RenderZhangBoard(pose, &radiance);
    }
    const common::CameraImage stored =
        tiny.renderer.Expose(radiance, tiny.plan.board_exposure_s, 1, 1, CaptureWindowOrigin(tiny.rig, id));
    ASSERT_EQ(stored.width, camera.intrinsics().width);
    cv::Mat gray(stored.height, stored.width, CV_8U);
    for (int y = 0; y < stored.height; ++y) {
      for (int x = 0; x < stored.width; ++x) {
        gray.at<uint8_t>(y, x) = static_cast<uint8_t>(stored.pixels[(size_t(y) * stored.width + x) * 3] >>
                                                      (stored.bits_per_sample - 8));
      }
    }
    std::vector<cv::Point2f> found;
    ASSERT_TRUE(cv::findChessboardCorners(gray, cv::Size(b.inner_cols, b.inner_rows), found));
    cv::cornerSubPix(gray, found, cv::Size(3, 3), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 50, 1e-4));
    const std::vector<model::Vec3> corners = BoardCorners(pose, b);
    // OpenCV may list the corners in reverse; compare with the nearer ordering.
    double forward = 0.0, backward = 0.0;
    for (size_t n = 0; n < corners.size(); ++n) {
      const model::Vec2 truth = *camera.Project(corners[n]);
      const cv::Point2f& f = found[n];
      const cv::Point2f& r = found[corners.size() - 1 - n];
      forward = std::max(forward, std::hypot(f.x - truth.x(), f.y - truth.y()));
      backward = std::max(backward, std::hypot(r.x - truth.x(), r.y - truth.y()));
    }
    worst = std::max(worst, std::min(forward, backward));
    model::Vec2 mean = model::Vec2::Zero();
    for (size_t n = 0; n < corners.size(); ++n) {
      const model::Vec2 truth = *camera.Project(corners[n]);
      const cv::Point2f& f = forward < backward ? found[n] : found[corners.size() - 1 - n];
      mean += (model::Vec2(f.x, f.y) - truth) / corners.size();
    }
    // No systematic shift (a half-pixel convention error would show here); the oblique holder
    // view (small foreshortened squares) is allowed more.
    EXPECT_LT(mean.norm(), holder ? 0.15 : 0.03) << "mean corner offset, px";
  }
  EXPECT_LT(worst, 0.35) << "largest corner error, px (measured 0.16 Zhang views, 0.28 holder)";
}

TEST(Capture, RigTruthRoundTrip) {
  TinyCapture tiny;
  const svbtdf::testing::TempFolder dir;
  const auto path = dir / "rig.json";
  WriteRigTruth(path, tiny.rig, tiny.plan);
  EXPECT_THROW(WriteRigTruth(path, tiny.rig, tiny.plan), common::Error);  // never overwritten
  const RigTruth truth = ReadRigTruth(path);
  EXPECT_EQ(truth.camera.fx, tiny.rig.config().intrinsics.fx);
  EXPECT_EQ(truth.camera.cy, tiny.rig.config().intrinsics.cy);
  EXPECT_EQ(truth.camera.distortion, tiny.rig.config().intrinsics.distortion);
  EXPECT_EQ(truth.rms_px, 0.0);
  EXPECT_LT((truth.pose.rotation - tiny.rig.config().pose.rotation).norm(), 1e-15);
  ASSERT_EQ(truth.dots.size(), tiny.rig.dots().size());
  EXPECT_EQ(truth.dots[7].position, tiny.rig.dots()[7].position);
  EXPECT_EQ(truth.capture.dot_exposures_s, tiny.plan.dot_exposures_s);
  EXPECT_EQ(truth.capture.zhang_boards.size(), tiny.plan.zhang_boards.size());
  EXPECT_THROW(ReadRigTruth(dir / "missing.json"), common::Error);
}

}  // namespace
}  // namespace svbtdf::simulate
