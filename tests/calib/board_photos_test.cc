// Calibrating a camera from a folder of board photos (`svbtdf calibrate --images`): rendered
// views of a known camera written as 8-bit and 12-in-16-bit PNG files give back its intrinsics,
// the camera calibration file round-trips, and bad photos are refused naming the file.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <opencv2/core/persistence.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "board_renderer.h"
#include "svbtdf/calib/board_photos.h"
#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "temp_folder.h"

namespace svbtdf::calib {
namespace {

CameraModel PhotoCamera() {
  CameraModel camera;
  camera.width = 640;
  camera.height = 480;
  camera.fx = 805.0;
  camera.fy = 803.0;
  camera.cx = 322.0;
  camera.cy = 237.0;
  camera.distortion = {-0.10, 0.04, 0.0, 0.0, 0.0};
  return camera;
}

class BoardPhotos : public ::testing::Test {
 protected:
  // Writes `count` rendered views; every third one as a 16-bit file holding 12-bit values.
  std::vector<std::string> WritePhotos(int count) {
    std::vector<std::string> files;
    int k = 0;
    for (const auto& [rvec, tvec] : testing::VariedBoardPoses(count, 5)) {
      const cv::Mat view = testing::RenderChessboard(board_, camera_, rvec, tvec, 0.01, k);
      std::string file = (folder_.path() / ("view" + std::to_string(k) + ".png")).string();
      if (k % 3 == 0) {
        cv::Mat twelve_bit;
        view.convertTo(twelve_bit, CV_16U, 4095.0 / 255.0);
        cv::imwrite(file, twelve_bit);
      } else {
        cv::imwrite(file, view);
      }
      files.push_back(file);
      ++k;
    }
    return files;
  }
  std::string ExpectRefused(const std::vector<std::string>& files) {
    try {
      CalibrateFromPhotos(files, board_, {}, /*progress=*/false);
      ADD_FAILURE() << "not refused";
    } catch (const common::Error& e) {
      return e.what();
    }
    return {};
  }

  svbtdf::testing::TempFolder folder_{"board_photos"};
  const BoardSpec board_ = BoardSpec::Parse("chessboard:9x6:20");
  const CameraModel camera_ = PhotoCamera();
};

TEST_F(BoardPhotos, RecoverTheCameraThatTookThem) {
  const std::vector<std::string> files = WritePhotos(10);
  const CalibrationReport report = CalibrateFromPhotos(files, board_, {}, /*progress=*/false);
  EXPECT_EQ(report.views.size(), files.size());
  EXPECT_GE(report.used_views(), 9);
  EXPECT_TRUE(report.views[0].used) << "the 16-bit photo: " << report.views[0].dropped_because;
  EXPECT_EQ(report.camera.width, camera_.width);
  EXPECT_LT(report.rms_px, 0.2);
  EXPECT_NEAR(report.camera.fx / camera_.fx, 1.0, 0.005);
  EXPECT_NEAR(report.camera.fy / camera_.fy, 1.0, 0.005);
  EXPECT_NEAR(report.camera.cx, camera_.cx, 2.0);
  EXPECT_NEAR(report.camera.cy, camera_.cy, 2.0);

  const std::filesystem::path json_path = folder_.path() / "camera.json";
  WriteCameraCalibration(json_path, board_, report);
  const nlohmann::json written = nlohmann::json::parse(common::ReadTextFile(json_path));
  EXPECT_EQ(written.at("format"), kCameraCalibrationFormat);
  EXPECT_EQ(written.at("version"), kCameraCalibrationVersion);
  EXPECT_EQ(written.at("board"), board_.ToString());
  EXPECT_DOUBLE_EQ(written.at("camera").at("fx").get<double>(), report.camera.fx);
  EXPECT_EQ(written.at("camera").at("views").size(), files.size());
}

TEST_F(BoardPhotos, AFileThatIsNoImageIsNamed) {
  std::vector<std::string> files = WritePhotos(4);
  const std::string bad = (folder_.path() / "notes.png").string();
  std::ofstream(bad) << "not a picture\n";
  files.insert(files.begin() + 2, bad);
  const std::string message = ExpectRefused(files);
  EXPECT_NE(message.find(bad), std::string::npos) << message;
  EXPECT_NE(message.find("cannot be read"), std::string::npos) << message;
}

TEST_F(BoardPhotos, APhotoOfAnotherSizeIsNamed) {
  std::vector<std::string> files = WritePhotos(4);
  const std::string other = (folder_.path() / "small.png").string();
  cv::imwrite(other, cv::Mat(100, 120, CV_8U, cv::Scalar(128)));
  files.push_back(other);
  const std::string message = ExpectRefused(files);
  EXPECT_NE(message.find(other), std::string::npos) << message;
  EXPECT_NE(message.find("120x100"), std::string::npos) << message;
}

}  // namespace
}  // namespace svbtdf::calib

namespace svbtdf::calib {
namespace {

// 25 photos of OpenCV's asymmetric 4 x 11 circle grid by a 640 x 512 camera, with their authors'
// calibration (shared/data/acircles-4x11-640x512/README.md states the tolerances checked here).
// Read in place, never copied.
class RealCircleGridPhotos : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!std::filesystem::exists(folder_ / "reference_calibration.xml")) {
      GTEST_SKIP() << "shared data absent: " << folder_;
    }
    for (const auto& entry : std::filesystem::directory_iterator(folder_ / "images")) {
      files_.push_back(entry.path().string());
    }
    std::sort(files_.begin(), files_.end());
    cv::FileStorage reference((folder_ / "reference_calibration.xml").string(), cv::FileStorage::READ);
    reference["camera_matrix_left"] >> reference_matrix_;
    reference["avg_reprojection_error_left"] >> reference_rms_;
  }
  CalibrationReport Calibrate(CalibrationOptions::LensModel lens_model) {
    CalibrationOptions options;
    options.lens_model = lens_model;
    return CalibrateFromPhotos(files_, board_, options, /*progress=*/false);
  }
  static void Print(const char* name, const CalibrationReport& r) {
    const ProjectionUncertainty& u = r.projection_uncertainty;
    std::printf("%s: fx %.3f (+-%.3f) fy %.3f (+-%.3f) cx %.3f (+-%.3f) cy %.3f (+-%.3f) RMS %.4f px, %d views; "
                "projection uncertainty centre %.4f corners %.4f %.4f %.4f %.4f worst %.4f px\n",
                name, r.camera.fx, r.intrinsics_std[0], r.camera.fy, r.intrinsics_std[1], r.camera.cx,
                r.intrinsics_std[2], r.camera.cy, r.intrinsics_std[3], r.rms_px, r.used_views(), u.centre_px,
                u.corners_px[0], u.corners_px[1], u.corners_px[2], u.corners_px[3], u.worst_px);
  }

  const std::filesystem::path folder_ = std::filesystem::path(SVBTDF_SHARED_DIR) / "data/acircles-4x11-640x512";
  const BoardSpec board_ = BoardSpec::Parse("acircles:4x11:20");
  std::vector<std::string> files_;
  cv::Mat reference_matrix_;
  double reference_rms_ = 0.0;
};

TEST_F(RealCircleGridPhotos, TheAuthorsCentredModelIsReproduced) {
  const CalibrationReport report = Calibrate(CalibrationOptions::LensModel::kCentred);
  Print("centred", report);
  ASSERT_EQ(files_.size(), 25u);
  EXPECT_EQ(report.used_views(), 25);
  EXPECT_EQ(report.lens_model, "centred");
  const double reference_fx = reference_matrix_.at<double>(0, 0);
  EXPECT_NEAR(report.camera.fx / reference_fx, 1.0, 0.003);
  EXPECT_DOUBLE_EQ(report.camera.fx, report.camera.fy);
  EXPECT_NEAR(report.rms_px, reference_rms_, 0.02);
  EXPECT_EQ(report.camera.distortion[2], 0.0);
  EXPECT_EQ(report.camera.distortion[3], 0.0);
  EXPECT_GT(report.intrinsics_std[0], 0.0);
  EXPECT_LT(report.intrinsics_std[0], 0.01 * report.camera.fx);
  // The principal point is held and the distortion vanishes at the centre: a ray through the
  // centre projects there whatever the focal length, so only the corners are uncertain, and
  // (square pixels, radial terms only, the principal point at the centre) all four alike.
  const ProjectionUncertainty& u = report.projection_uncertainty;
  EXPECT_LT(u.centre_px, 0.01);
  for (double corner : u.corners_px) {
    EXPECT_GT(corner, 0.1);
    EXPECT_NEAR(corner / u.corners_px[0], 1.0, 1e-6);
  }
  EXPECT_GE(u.worst_px, u.corners_px[0] - 1e-12);
}

TEST_F(RealCircleGridPhotos, TheFullModelAgreesWithOpenCv) {
  const CalibrationReport report = Calibrate(CalibrationOptions::LensModel::kFull);
  Print("full", report);
  EXPECT_EQ(report.used_views(), 25);
  EXPECT_EQ(report.lens_model, "full") << report.narrow_lens_because;
  EXPECT_NEAR(report.camera.fx / 527.5, 1.0, 0.005);
  EXPECT_NEAR(report.camera.fy / 527.9, 1.0, 0.005);
  EXPECT_NEAR(report.camera.cx, 313.6, 2.0);
  EXPECT_NEAR(report.camera.cy, 255.5, 2.0);
  EXPECT_NEAR(report.rms_px, 0.066, 0.02);
  for (int c = 0; c < 4; ++c) {
    EXPECT_GT(report.intrinsics_std[c], 0.0);
    EXPECT_LT(report.intrinsics_std[c], 5.0);
  }
  // At the centre a ray's projection moves with the principal point alone (the focal length and
  // the distortion act in proportion to the distance from it), so the propagated covariance must
  // give back OpenCV's own standard deviation of the principal point there (computed by OpenCV
  // from its own Jacobian: an independent check of the propagated covariance).
  const ProjectionUncertainty& u = report.projection_uncertainty;
  const double principal_point_std = std::max(report.intrinsics_std[2], report.intrinsics_std[3]);
  EXPECT_NEAR(u.centre_px / principal_point_std, 1.0, 0.05);
  // The corners are extrapolated from fewer board points: less certain than the centre.
  for (double corner : u.corners_px) EXPECT_GT(corner, u.centre_px);
  EXPECT_GE(u.worst_px, *std::max_element(u.corners_px.begin(), u.corners_px.end()) - 1e-12);
}

}  // namespace
}  // namespace svbtdf::calib
