// The HDR merge, the linearisation and response recovery against synthetic exposure stacks of a
// known scene.
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/core.hpp>
#include <random>

#include "svbtdf/calib/radiometry.h"
#include "svbtdf/common/error.h"

namespace svbtdf::calib {
namespace {

// A scene spanning four decades of radiance (per second at unit gain), left to right.
cv::Mat SceneRadiance(int width, int height) {
  cv::Mat radiance(height, width, CV_32F);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) radiance.at<float>(y, x) = static_cast<float>(10.0 * std::pow(10.0, 4.0 * x / (width - 1)));
  }
  return radiance;
}

double SrgbLike(double linear) {  // linear in [0,1] -> encoded in [0,1]
  return linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1 / 2.4) - 0.055;
}

TEST(HdrMerge, LinearSixteenBitBracketsRecoverTheSceneWithinShotNoise) {
  const cv::Mat scene = SceneRadiance(200, 4);
  std::mt19937_64 rng(1);
  std::vector<Exposure> brackets;
  const cv::Mat dark(scene.size(), CV_16U, cv::Scalar(64));
  for (double t : {1e-3, 1e-2, 1e-1, 1.0}) {
    cv::Mat image(scene.size(), CV_16U);
    for (int y = 0; y < scene.rows; ++y) {
      for (int x = 0; x < scene.cols; ++x) {
        const double electrons = scene.at<float>(y, x) * t * 60.0;  // signal in counts
        std::poisson_distribution<int64_t> shot(std::max(electrons, 1e-9));
        const double value = 64.0 + std::min<double>(shot(rng), 70000.0);
        image.at<uint16_t>(y, x) = static_cast<uint16_t>(std::min(value, 65535.0));
      }
    }
    brackets.push_back({image, t, 1.0, "t=" + std::to_string(t)});
  }
  Radiometry linear;  // 16-bit, the top 5% of the range unusable
  linear.saturation_dn = 0.95 * 65535;
  const HdrResult hdr = MergeExposures(brackets, dark, linear);
  // Each pixel's error must be within 4 standard deviations of the shot noise of its best
  // unsaturated exposure, and the mean error within 1%.
  double sum_error = 0;
  int checked = 0;
  for (int y = 0; y < scene.rows; ++y) {
    for (int x = 0; x < scene.cols; ++x) {
      ASSERT_EQ(hdr.valid.at<uint8_t>(y, x), 255) << x;
      const double expected = scene.at<float>(y, x) * 60.0;
      double best_counts = 0;
      for (const Exposure& e : brackets) {
        const double counts = expected * e.exposure_s;
        if (counts + 64 < 0.95 * 65535) best_counts = std::max(best_counts, counts);
      }
      const double error = hdr.radiance.at<float>(y, x) / expected - 1.0;
      EXPECT_LT(std::abs(error), 4.0 / std::sqrt(best_counts) + 1e-3) << "x " << x << " counts " << best_counts;
      sum_error += std::abs(error);
      ++checked;
    }
  }
  EXPECT_LT(sum_error / checked, 0.01);
}

TEST(HdrMerge, MasksPixelsThatAreSaturatedEverywhere) {
  const cv::Mat bright(2, 2, CV_16U, cv::Scalar(65535));
  const HdrResult hdr = MergeExposures({{bright, 0.01, 1.0, "a"}, {bright, 0.1, 1.0, "b"}}, cv::Mat(), Radiometry{});
  EXPECT_EQ(hdr.valid.at<uint8_t>(0, 0), 0);
  EXPECT_EQ(hdr.saturated.at<uint8_t>(0, 0), 255);
}

TEST(HdrMerge, ErrorsNameTheOffendingImage) {
  const cv::Mat a(4, 4, CV_16U, cv::Scalar(100)), b(4, 5, CV_16U, cv::Scalar(100));
  try {
    MergeExposures({{a, 0.01, 1.0, "dot/q0001/e0"}, {b, 0.1, 1.0, "dot/q0001/e1"}}, cv::Mat(), Radiometry{});
    FAIL();
  } catch (const common::Error& e) {
    EXPECT_NE(std::string(e.what()).find("dot/q0001/e1"), std::string::npos);
  }
  EXPECT_THROW(MergeExposures({{a, 0.0, 1.0, "zero"}}, cv::Mat(), Radiometry{}), common::Error);
}

// The merge is the maximum-likelihood rate: the sum of the usable values over the sum of their
// exposures; saturated and non-finite samples are skipped, and a sample with none is NaN.
TEST(HdrAccumulator, SumsUsableValuesOverTheirExposures) {
  HdrAccumulator merge(3, 2);
  const float short_values[] = {1, 2, 10, 20, NAN, 5};
  const uint8_t short_saturated[] = {0, 0, 0};
  const float long_values[] = {9, 18, 99, 99, 7, 7};
  const uint8_t long_saturated[] = {0, 1, 1};
  merge.Add(short_values, short_saturated, 0.1);
  merge.Add(long_values, long_saturated, 0.9);
  const std::vector<float> rates = merge.Rates();
  EXPECT_FLOAT_EQ(rates[0], 10.0f);  // (1 + 9) / (0.1 + 0.9)
  EXPECT_FLOAT_EQ(rates[1], 20.0f);
  EXPECT_FLOAT_EQ(rates[2], 100.0f);  // the long bracket saturated: 10 / 0.1
  EXPECT_FLOAT_EQ(rates[3], 200.0f);
  EXPECT_TRUE(std::isnan(rates[4]));  // not finite, then saturated
  EXPECT_FALSE(merge.AnyUsable(2));
  EXPECT_TRUE(merge.AnyUsable(0));
}

TEST(Radiometry, TableLinearisationInterpolatesAfterTheBlackOffset) {
  Radiometry r;
  r.response = "table";
  r.bit_depth = 8;
  r.black_offset_dn = 5;
  r.inverse_response = {0.0, 1.0, 4.0};  // at raw 0, 127.5 and 255
  EXPECT_DOUBLE_EQ(r.Linearize(5), 0.0);
  EXPECT_DOUBLE_EQ(r.Linearize(5 + 127.5), 1.0);
  EXPECT_DOUBLE_EQ(r.Linearize(5 + 191.25), 2.5);
  EXPECT_DOUBLE_EQ(r.Linearize(1000), 4.0);  // clamped
  const std::vector<float> table = r.LinearTable(256);
  ASSERT_EQ(table.size(), 256u);
  EXPECT_FLOAT_EQ(table[5], 0.0f);
  Radiometry linear;
  linear.black_offset_dn = 64;
  EXPECT_DOUBLE_EQ(linear.Linearize(100), 36.0);
}

TEST(ResponseRecovery, DebevecRecoversAnSrgbLikeCurveFromAnEightBitStack) {
  const cv::Mat scene = SceneRadiance(256, 32);
  std::vector<cv::Mat> images;
  std::vector<double> times;
  std::mt19937_64 rng(2);
  std::normal_distribution<double> noise(0.0, 0.3);
  for (double t : {1e-4, 4e-4, 1.6e-3, 6.4e-3, 2.56e-2}) {
    cv::Mat image(scene.size(), CV_8UC3);
    for (int y = 0; y < scene.rows; ++y) {
      for (int x = 0; x < scene.cols; ++x) {
        const double linear = std::min(1.0, scene.at<float>(y, x) * t / 10.0);
        const double value = std::clamp(255.0 * SrgbLike(linear) + noise(rng), 0.0, 255.0);
        image.at<cv::Vec3b>(y, x) = cv::Vec3b::all(static_cast<uint8_t>(std::lround(value)));
      }
    }
    images.push_back(image);
    times.push_back(t);
  }
  const Radiometry response = RecoverResponse(images, times, ResponseMethod::kDebevec, "stack");
  EXPECT_EQ(response.response, "table");
  EXPECT_EQ(response.bit_depth, 8);
  ASSERT_EQ(response.inverse_response.size(), 256u);
  // Compare the recovered inverse response (up to scale) with the true inverse sRGB curve over
  // the well-exposed range (values 30 to 220: Debevec's smoothness prior bends the ends); the
  // ratio to the truth must be flat within 5%.
  auto inverse_srgb = [](double v) { return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4); };
  const double reference = response.Linearize(128) / inverse_srgb(128 / 255.0);
  for (int v = 30; v <= 220; v += 10) {
    const double ratio = response.Linearize(v) / inverse_srgb(v / 255.0) / reference;
    EXPECT_NEAR(ratio, 1.0, 0.05) << "camera value " << v;
  }
}

}  // namespace
}  // namespace svbtdf::calib
