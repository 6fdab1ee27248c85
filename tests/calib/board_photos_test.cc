// Calibrating a camera from a folder of board photos (`svbtdf calibrate --images`): rendered
// views of a known camera written as 8-bit and 12-in-16-bit PNG files give back its intrinsics,
// the camera calibration file round-trips, and bad photos are refused naming the file.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

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
