#include "board_renderer.h"

#include <random>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace svbtdf::calib::testing {

cv::Mat RenderChessboard(const BoardSpec& board, const CameraModel& camera, const cv::Vec3d& rvec,
                         const cv::Vec3d& tvec, double noise_sigma, uint64_t seed) {
  constexpr int kSuper = 2;
  const cv::Size size(camera.width, camera.height);
  // Undistorted (ideal pinhole) normalised coordinates of every supersampled pixel centre.
  std::vector<cv::Point2f> pixels;
  pixels.reserve(static_cast<size_t>(size.area()) * kSuper * kSuper);
  for (int y = 0; y < size.height * kSuper; ++y) {
    for (int x = 0; x < size.width * kSuper; ++x) {
      pixels.emplace_back((x + 0.5f) / kSuper - 0.5f, (y + 0.5f) / kSuper - 0.5f);
    }
  }
  std::vector<cv::Point2f> normalised;
  cv::undistortPoints(pixels, normalised, camera.CameraMatrix(), camera.DistortionCoefficients(), cv::noArray(),
                      cv::noArray(), cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 20, 1e-9));
  // Intersect each ray with the board plane z = 0 in board coordinates.
  cv::Matx33d rotation;
  cv::Rodrigues(rvec, rotation);
  const cv::Matx33d to_board = rotation.t();
  const cv::Vec3d camera_in_board = -(to_board * tvec);
  cv::Mat super(size.height * kSuper, size.width * kSuper, CV_32F);
  const double square = board.square_mm;
  for (int y = 0; y < super.rows; ++y) {
    for (int x = 0; x < super.cols; ++x) {
      const cv::Point2f& n = normalised[static_cast<size_t>(y) * super.cols + x];
      const cv::Vec3d ray = to_board * cv::Vec3d(n.x, n.y, 1.0);
      float value = 0.35f;  // the background around the board
      if (std::abs(ray[2]) > 1e-12) {
        const double t = -camera_in_board[2] / ray[2];
        if (t > 0) {
          const double bx = camera_in_board[0] + t * ray[0], by = camera_in_board[1] + t * ray[1];
          // Squares span [-1, cols] x [-1, rows] in square units around the inner corners, with a
          // white margin of one square around the pattern.
          const double u = bx / square + 1.0, v = by / square + 1.0;
          if (u >= -1 && v >= -1 && u < board.cols + 2 && v < board.rows + 2) {
            const bool inside = u >= 0 && v >= 0 && u < board.cols + 1 && v < board.rows + 1;
            const bool black = inside && ((static_cast<int>(std::floor(u)) + static_cast<int>(std::floor(v))) % 2 == 0);
            value = black ? 0.05f : 0.9f;
          }
        }
      }
      super.at<float>(y, x) = value;
    }
  }
  cv::Mat image;
  cv::resize(super, image, size, 0, 0, cv::INTER_AREA);
  if (noise_sigma > 0) {
    cv::RNG rng(seed);
    cv::Mat noise(size, CV_32F);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, noise_sigma);
    image += noise;
  }
  cv::Mat gray;
  image.convertTo(gray, CV_8U, 255.0);
  return gray;
}

std::vector<std::pair<cv::Vec3d, cv::Vec3d>> VariedBoardPoses(int count, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> tilt(-0.6, 0.6), shift(-40, 40);
  std::vector<std::pair<cv::Vec3d, cv::Vec3d>> poses;
  for (int k = 0; k < count; ++k) {
    poses.push_back({cv::Vec3d(tilt(rng), tilt(rng), 0.3 * tilt(rng)),
                     cv::Vec3d(-100 + shift(rng), -70 + shift(rng), 520 + 2 * shift(rng))});
  }
  return poses;
}

}  // namespace svbtdf::calib::testing
