// Zhang calibration against a known camera: rendered chessboard views must give back the
// intrinsics within the tolerances of issue 4 (focal lengths 0.5%, principal point 2 px).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <opencv2/calib3d.hpp>
#include <cmath>
#include <cstdio>
#include <random>

#include "board_renderer.h"
#include "svbtdf/calib/camera_calibration.h"
#include "svbtdf/common/error.h"

namespace svbtdf::calib {
namespace {

CameraModel TrueCamera() {
  CameraModel camera;
  camera.width = 800;
  camera.height = 600;
  camera.fx = 1020.0;
  camera.fy = 1017.0;
  camera.cx = 407.0;
  camera.cy = 296.0;
  camera.distortion = {-0.12, 0.05, 0.0008, -0.0005, 0.0};
  return camera;
}

std::vector<BoardDetection> DetectRenderedViews(const BoardSpec& board, const CameraModel& camera, int count) {
  std::vector<BoardDetection> detections;
  int k = 0;
  for (const auto& [rvec, tvec] : testing::VariedBoardPoses(count, 17)) {
    const cv::Mat image = testing::RenderChessboard(board, camera, rvec, tvec, 0.01, k);
    detections.push_back(DetectBoard(image, board, "view" + std::to_string(k++)));
  }
  return detections;
}

TEST(BoardSpec, ParsesAndRejects) {
  const BoardSpec chess = BoardSpec::Parse("chessboard:9x6:25");
  EXPECT_EQ(chess.cols, 9);
  EXPECT_EQ(chess.rows, 6);
  EXPECT_DOUBLE_EQ(chess.square_mm, 25.0);
  EXPECT_EQ(chess.CornerPositions().size(), 54u);
  const BoardSpec charuco = BoardSpec::Parse("charuco:8x6:30:22:DICT_4X4_50");
  EXPECT_EQ(charuco.kind, BoardSpec::Kind::kCharuco);
  EXPECT_EQ(charuco.CornerPositions().size(), 35u);
  const BoardSpec acircles = BoardSpec::Parse("acircles:4x11:20");
  EXPECT_EQ(acircles.kind, BoardSpec::Kind::kAsymmetricCircles);
  EXPECT_EQ(acircles.ToString(), "acircles:4x11:20");
  const std::vector<cv::Point3f> centres = acircles.CornerPositions();
  ASSERT_EQ(centres.size(), 44u);
  EXPECT_EQ(centres[4], cv::Point3f(20, 20, 0));  // the second row starts one spacing in
  EXPECT_EQ(centres[7], cv::Point3f(140, 20, 0));
  const BoardSpec circles = BoardSpec::Parse("circles:7x5:12.5");
  EXPECT_EQ(circles.kind, BoardSpec::Kind::kSymmetricCircles);
  EXPECT_EQ(circles.CornerPositions()[8], cv::Point3f(12.5f, 12.5f, 0));
  EXPECT_EQ(BoardSpec::Parse(circles.ToString()).kind, circles.kind);
  for (const char* bad : {"chess:9x6:25", "chessboard:9x6", "chessboard:1x6:25", "chessboard:9x6:0",
                          "charuco:8x6:30:40", "charuco:8x6:30:20:NOPE", "chessboard:99999999999x6:25",
                          "acircles:4x11", "acircles:4x11:0", "circles:4:20", "xcircles:4x11:20"}) {
    EXPECT_THROW(BoardSpec::Parse(bad), common::Error) << bad;
  }
  try {
    BoardSpec::Parse("acircles:4x11:0", "rig.board.spec");
  } catch (const common::Error& e) {
    EXPECT_NE(std::string(e.what()).find("rig.board.spec"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("circle spacing"), std::string::npos) << e.what();
  }
}

TEST(CameraCalibration, RecoversKnownIntrinsicsFromRenderedViews) {
  const BoardSpec board = BoardSpec::Parse("chessboard:9x6:20");
  const CameraModel truth = TrueCamera();
  const std::vector<BoardDetection> detections = DetectRenderedViews(board, truth, 12);
  const CalibrationReport report = CalibrateCamera(detections, cv::Size(truth.width, truth.height));
  RecordProperty("fx_relative_error", std::to_string(report.camera.fx / truth.fx - 1));
  std::printf("rms %.4f px, fx %.3f (truth %.1f), fy %.3f, cx %.3f, cy %.3f, k1 %.4f\n", report.rms_px,
              report.camera.fx, truth.fx, report.camera.fy, report.camera.cx, report.camera.cy,
              report.camera.distortion[0]);
  EXPECT_GE(report.used_views(), 10);
  EXPECT_LT(report.rms_px, 0.2);
  EXPECT_NEAR(report.camera.fx / truth.fx, 1.0, 0.005);
  EXPECT_NEAR(report.camera.fy / truth.fy, 1.0, 0.005);
  EXPECT_NEAR(report.camera.cx, truth.cx, 2.0);
  EXPECT_NEAR(report.camera.cy, truth.cy, 2.0);
  EXPECT_NEAR(report.camera.distortion[0], truth.distortion[0], 0.03);
  EXPECT_GT(report.intrinsics_std[0], 0.0);
  const nlohmann::json json = ToJson(report);
  EXPECT_DOUBLE_EQ(json["fx"].get<double>(), report.camera.fx);
  EXPECT_EQ(json["distortion"].size(), 5u);
}

// A 6-degree lens (240 x 200 pixels, f = 2200 px) seeing a 6 x 4 board of 7 mm squares at 1 m,
// the simulator's old set-up: the full model's principal point is ill-determined, so the views are
// refitted with the narrow-lens model (square pixels, centred principal point, k1 only). Corners are exact projections plus 0.08 px noise.
TEST(CameraCalibration, ANarrowLensFallsBackToTheNarrowLensModel) {
  const BoardSpec board = BoardSpec::Parse("chessboard:6x4:7");
  const cv::Matx33d k(2200, 0, 122.6, 0, 2201, 97.7, 0, 0, 1);
  const std::vector<double> distortion = {-0.12, 0.4, 0.0004, -0.0003, 0.0};
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.08);
  std::vector<BoardDetection> detections;
  for (int view = 0; view < 12; ++view) {
    const double tilt = (20.0 + 20.0 * uniform(rng)) * CV_PI / 180.0, axis = 2 * CV_PI * view / 12.0;
    const cv::Vec3d rvec(tilt * std::cos(axis), tilt * std::sin(axis), 0.0);
    const cv::Vec3d tvec(-17.5 + 10 * (uniform(rng) - 0.5), -10.5 + 8 * (uniform(rng) - 0.5), 1000.0 + 100 * (uniform(rng) - 0.5));
    BoardDetection detection;
    detection.source = "view" + std::to_string(view);
    detection.found = true;
    detection.object_points = board.CornerPositions();
    std::vector<cv::Point2f> projected;
    cv::projectPoints(detection.object_points, rvec, tvec, k, distortion, projected);
    for (cv::Point2f& p : projected) p += cv::Point2f(noise(rng), noise(rng));
    detection.image_points = projected;
    detections.push_back(detection);
  }
  const CalibrationReport narrow = CalibrateCamera(detections, cv::Size(240, 200));
  std::printf("narrow-lens model: fx %.1f +- %.1f (truth 2200), because %s\n", narrow.camera.fx, narrow.intrinsics_std[0],
              narrow.narrow_lens_because.c_str());
  EXPECT_NE(narrow.narrow_lens_because.find("principal point"), std::string::npos);
  EXPECT_DOUBLE_EQ(narrow.camera.fx, narrow.camera.fy);
  EXPECT_DOUBLE_EQ(narrow.camera.cx, 119.5);  // the image centre
  // At 6 degrees even the narrow model knows f only to a few percent; the truth lies within
  // three of its reported standard deviations.
  EXPECT_LT(std::abs(narrow.camera.fx - 2200.0), 3 * narrow.intrinsics_std[0]);
  CalibrationOptions full;
  full.max_principal_point_std_fraction = 0;
  const CalibrationReport free = CalibrateCamera(detections, cv::Size(240, 200), full);
  EXPECT_TRUE(free.narrow_lens_because.empty());
  EXPECT_GT(free.intrinsics_std[2], 0.02 * 240);
}

TEST(CameraCalibration, DropsAndReportsViewsWithoutABoardAndOutliers) {
  const BoardSpec board = BoardSpec::Parse("chessboard:9x6:20");
  const CameraModel truth = TrueCamera();
  std::vector<BoardDetection> detections = DetectRenderedViews(board, truth, 8);
  // A blank image: the board is not found.
  detections.push_back(DetectBoard(cv::Mat(600, 800, CV_8U, cv::Scalar(128)), board, "blank.png"));
  // A view whose corners were mislabelled (rows reversed): a gross outlier.
  BoardDetection corrupt = detections.front();
  corrupt.source = "shuffled.png";
  std::reverse(corrupt.image_points.begin(), corrupt.image_points.begin() + 9);
  detections.push_back(corrupt);
  const CalibrationReport report = CalibrateCamera(detections, cv::Size(truth.width, truth.height));
  ASSERT_EQ(report.views.size(), detections.size());
  EXPECT_FALSE(report.views[8].used);
  EXPECT_NE(report.views[8].dropped_because.find("not found"), std::string::npos);
  EXPECT_FALSE(report.views[9].used);
  EXPECT_NE(report.views[9].dropped_because.find("outlier"), std::string::npos);
  EXPECT_NEAR(report.camera.fx / truth.fx, 1.0, 0.005);
}

TEST(CameraCalibration, TooFewViewsIsAClearError) {
  const BoardSpec board = BoardSpec::Parse("chessboard:9x6:20");
  const CameraModel truth = TrueCamera();
  std::vector<BoardDetection> detections = DetectRenderedViews(board, truth, 2);
  try {
    CalibrateCamera(detections, cv::Size(truth.width, truth.height));
    FAIL() << "expected an error";
  } catch (const common::Error& e) {
    EXPECT_NE(std::string(e.what()).find("2 usable board views"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace svbtdf::calib
