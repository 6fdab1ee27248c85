// render::RelativeRmse, Ssim and ToSrgb8 on images whose answers are known.
#include "svbtdf/render/image_metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "svbtdf/common/error.h"

namespace svbtdf::render {
namespace {

common::FloatImage Noise(int w, int h, uint64_t seed, double mean, double spread) {
  common::FloatImage image(w, h, 3);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-spread, spread);
  for (float& v : image.pixels) v = static_cast<float>(mean + u(rng));
  return image;
}

TEST(ImageMetrics, RelativeRmseIsTheNormalisedDifference) {
  const common::FloatImage reference(16, 16, 3, 0.5f);
  common::FloatImage brighter = reference;
  for (float& v : brighter.pixels) v *= 1.1f;
  EXPECT_NEAR(RelativeRmse(brighter, reference), 0.1, 1e-6);
  EXPECT_EQ(RelativeRmse(reference, reference), 0.0);
  EXPECT_THROW(RelativeRmse(common::FloatImage(8, 8, 3), reference), common::Error);
  EXPECT_THROW(RelativeRmse(reference, common::FloatImage(16, 16, 3)), common::Error);
}

TEST(ImageMetrics, SsimIsOneForTheSameImageAndFallsWithStructureLost) {
  const common::FloatImage a = Noise(48, 40, 1, 0.3, 0.2);
  EXPECT_NEAR(Ssim(a, a), 1.0, 1e-12);
  common::FloatImage slightly = a, unrelated = Noise(48, 40, 2, 0.3, 0.2);
  for (float& v : slightly.pixels) v *= 1.02f;
  const double near = Ssim(slightly, a), far = Ssim(unrelated, a);
  EXPECT_GT(near, 0.98);
  EXPECT_LT(far, 0.1);  // independent noise of the same statistics shares no structure
  // A uniform image against itself shifted in brightness: only the luminance term remains.
  EXPECT_NEAR(Ssim(common::FloatImage(20, 20, 3, 0.05f), common::FloatImage(20, 20, 3, 0.8f)), 0.507, 0.01);
  EXPECT_THROW(Ssim(common::FloatImage(8, 8, 3), common::FloatImage(8, 8, 3)), common::Error);
}

TEST(ImageMetrics, ToSrgb8EncodesLinearValues) {
  common::FloatImage image(3, 1, 3);
  for (int c = 0; c < 3; ++c) image.at(0, 0, c) = 0.0f, image.at(1, 0, c) = 0.5f, image.at(2, 0, c) = 4.0f;
  const std::vector<uint8_t> rgb = ToSrgb8(image);
  EXPECT_EQ(rgb[0], 0);
  EXPECT_EQ(rgb[3], 188);  // linear 0.5 is sRGB 0.735
  EXPECT_EQ(rgb[6], 255);  // clamped
  EXPECT_EQ(ToSrgb8(image, 0.125)[6], 188);
}

}  // namespace
}  // namespace svbtdf::render
