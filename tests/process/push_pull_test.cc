// PushPullResampler (fit/src/push_pull.cc): scattered light samples resampled onto the light
// hemicube. A constant stays constant; samples at cell centres come back as they went in; cells
// without data are filled from their neighbours with values inside the range of the input; a
// smooth function sampled densely is reproduced at resolution 16.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "svbtdf/common/error.h"
#include "svbtdf/process/push_pull.h"
#include "svbtdf/model/hemicube.h"

namespace svbtdf::process {
namespace {

struct Samples {
  std::vector<model::Vec3> light;  // i.z < 0
  std::vector<float> values, weights;
  void Add(const model::Vec3& upper, float value, float weight = 1.0f) {
    light.push_back(model::FlipZ(upper.normalized()));
    values.push_back(value);
    weights.push_back(weight);
  }
};

struct Resampled {
  std::vector<float> values, confidence;
};

Resampled Resample(const PushPullResampler& resampler, const Samples& samples) {
  Resampled out;
  resampler.Resample(samples.light, samples.values, samples.weights, &out.values, &out.confidence);
  EXPECT_EQ(out.values.size(), static_cast<size_t>(resampler.grid().num_cells()));
  EXPECT_EQ(out.confidence.size(), out.values.size());
  return out;
}

// Uniform directions on the upper hemisphere (z > 0.01, clear of the horizon).
std::vector<model::Vec3> UniformUpper(int count, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<model::Vec3> out;
  while (static_cast<int>(out.size()) < count) {
    const double z = u(rng), phi = 2 * model::kPi * u(rng), r = std::sqrt(std::max(0.0, 1 - z * z));
    if (z > 0.01) out.emplace_back(r * std::cos(phi), r * std::sin(phi), z);
  }
  return out;
}

// A smooth function of the (upper) direction, between 0.2 and 1.2.
double Smooth(const model::Vec3& d) { return 0.6 + 0.3 * d.x() - 0.2 * d.y() + 0.3 * d.z() * d.z(); }

TEST(PushPull, RefusesAResolutionThatIsNotAPowerOfTwoAndMismatchedInputs) {
  EXPECT_THROW(PushPullResampler(model::Hemicube(12)), common::Error);
  const PushPullResampler resampler{model::Hemicube(8)};
  std::vector<float> values, confidence;
  try {
    resampler.Resample({model::Vec3(0, 0, -1)}, {1.0f, 2.0f}, {1.0f}, &values, &confidence);
    FAIL() << "mismatched lengths were accepted";
  } catch (const common::Error& e) {
    EXPECT_EQ(e.kind(), common::ErrorKind::kInvalidInput);
  }
}

TEST(PushPull, AConstantStaysConstantEverywhere) {
  const PushPullResampler resampler{model::Hemicube(16)};
  Samples samples;
  // Sparse, clumped samples (a quarter of the hemisphere) with uneven weights.
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<float> weight(0.1f, 3.0f);
  for (const model::Vec3& d : UniformUpper(400, 1)) {
    if (d.x() > 0 && d.y() > 0) samples.Add(d, 0.75f, weight(rng));
  }
  ASSERT_GT(samples.light.size(), 50u);
  const Resampled out = Resample(resampler, samples);
  for (size_t c = 0; c < out.values.size(); ++c) ASSERT_NEAR(out.values[c], 0.75f, 1e-5f) << "cell " << c;
}

TEST(PushPull, SamplesAtCellCentresAreReproduced) {
  for (int resolution : {4, 16}) {
    const PushPullResampler resampler{model::Hemicube(resolution)};
    const model::Hemicube& grid = resampler.grid();
    Samples samples;
    std::mt19937_64 rng(resolution);
    std::uniform_real_distribution<float> value(0.0f, 5.0f);
    std::vector<float> truth;
    for (int c = 0; c < grid.num_cells(); ++c) {
      truth.push_back(value(rng));
      samples.Add(grid.CellCenter(c), truth.back());
    }
    const Resampled out = Resample(resampler, samples);
    for (int c = 0; c < grid.num_cells(); ++c) {
      EXPECT_NEAR(out.values[c], truth[c], 1e-4f * (1.0f + truth[c])) << "resolution " << resolution << " cell " << c;
      EXPECT_NEAR(out.confidence[c], 1.0f, 1e-4f) << "resolution " << resolution << " cell " << c;
    }
  }
}

TEST(PushPull, MissingWeightsAndNonFiniteValuesAreIgnored) {
  const PushPullResampler resampler{model::Hemicube(8)};
  Samples clean;
  for (const model::Vec3& d : UniformUpper(300, 5)) clean.Add(d, static_cast<float>(Smooth(d)));
  Samples noisy = clean;
  noisy.Add(model::Vec3(0.1, 0.2, 1), 1000.0f, 0.0f);      // weight 0: missing
  noisy.Add(model::Vec3(-0.3, 0.1, 1), std::nanf(""), 1.0f);  // not a number
  noisy.Add(model::Vec3(0.5, -0.5, 0.3), INFINITY, 2.0f);
  const Resampled a = Resample(resampler, clean), b = Resample(resampler, noisy);
  EXPECT_EQ(a.values, b.values);
  EXPECT_EQ(a.confidence, b.confidence);
}

// One sample anywhere: every cell takes its value (the pull reaches the top of the pyramid).
TEST(PushPull, ASingleSampleFillsTheWholeHemicube) {
  const PushPullResampler resampler{model::Hemicube(16)};
  Samples samples;
  samples.Add(model::Vec3(0.3, -0.7, 0.4), 2.5f);
  const Resampled out = Resample(resampler, samples);
  int supported = 0;
  for (size_t c = 0; c < out.values.size(); ++c) {
    ASSERT_NEAR(out.values[c], 2.5f, 1e-5f) << "cell " << c;
    if (out.confidence[c] > 0) ++supported;
  }
  EXPECT_GE(supported, 1);
  EXPECT_LE(supported, 4);  // the bilinear footprint of one sample
}

// Empty cells take their values from the nearest data: of two samples (1 near +x, 0 near -x),
// the side of each is filled with values nearer its own; nothing leaves the input range.
TEST(PushPull, EmptyCellsAreFilledFromTheirNeighboursWithinTheInputRange) {
  const PushPullResampler resampler{model::Hemicube(16)};
  const model::Hemicube& grid = resampler.grid();
  Samples samples;
  samples.Add(model::Vec3(1, 0.2, 0.2), 1.0f);
  samples.Add(model::Vec3(-1, -0.2, 0.2), 0.0f);
  const Resampled out = Resample(resampler, samples);
  for (size_t c = 0; c < out.values.size(); ++c) {
    ASSERT_GE(out.values[c], 0.0f) << "cell " << c;
    ASSERT_LE(out.values[c], 1.0f) << "cell " << c;
  }
  // Three cells above each sample: outside its bilinear footprint.
  const int near_one = grid.CellOf(model::Vec3(1, 0.2, 0.6)), near_zero = grid.CellOf(model::Vec3(-1, -0.2, 0.6));
  EXPECT_EQ(out.confidence[near_one], 0.0f);  // not under either sample's footprint
  EXPECT_EQ(out.confidence[near_zero], 0.0f);
  EXPECT_GT(out.values[near_one], 0.5f);
  EXPECT_LT(out.values[near_zero], 0.5f);
  EXPECT_NEAR(out.values[grid.CellOf(model::Vec3(1, 0.2, 0.2))], 1.0f, 1e-5f);
  EXPECT_NEAR(out.values[grid.CellOf(model::Vec3(-1, -0.2, 0.2))], 0.0f, 1e-5f);

  // Random sparse data of a wide range: every cell, covered or not, stays within it.
  Samples sparse;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<float> value(-2.0f, 7.0f);
  float lo = 1e9f, hi = -1e9f;
  for (const model::Vec3& d : UniformUpper(60, 12)) {
    sparse.Add(d, value(rng));
    lo = std::min(lo, sparse.values.back());
    hi = std::max(hi, sparse.values.back());
  }
  const Resampled filled = Resample(resampler, sparse);
  int empty = 0;
  for (size_t c = 0; c < filled.values.size(); ++c) {
    ASSERT_TRUE(std::isfinite(filled.values[c])) << "cell " << c;
    EXPECT_GE(filled.values[c], lo - 1e-5f) << "cell " << c;
    EXPECT_LE(filled.values[c], hi + 1e-5f) << "cell " << c;
    if (filled.confidence[c] == 0.0f) ++empty;
  }
  EXPECT_GT(empty, grid.num_cells() / 2);  // 60 samples leave most of the 768 cells empty
}

// A smooth function sampled densely (about 40 samples per cell) is reproduced at resolution 16
// at every cell centre (measured: within 0.005), and a hole of radius 25 degrees cut out of the
// data is filled close to it.
TEST(PushPull, ASmoothFunctionIsReproducedAtResolution16) {
  const PushPullResampler resampler{model::Hemicube(16)};
  const model::Hemicube& grid = resampler.grid();
  const model::Vec3 hole_centre = model::Vec3(0.4, 0.3, 0.6).normalized();
  const double hole_cos = std::cos(25.0 * model::kPi / 180.0);
  Samples dense, holed;
  for (const model::Vec3& d : UniformUpper(30000, 21)) {
    dense.Add(d, static_cast<float>(Smooth(d)));
    if (d.dot(hole_centre) < hole_cos) holed.Add(d, static_cast<float>(Smooth(d)));
  }
  const Resampled out = Resample(resampler, dense), filled = Resample(resampler, holed);
  double worst = 0, worst_in_hole = 0;
  int in_hole = 0;
  for (int c = 0; c < grid.num_cells(); ++c) {
    const model::Vec3 centre = grid.CellCenter(c);
    worst = std::max(worst, std::abs(out.values[c] - Smooth(centre)));
    if (centre.dot(hole_centre) > std::cos(15.0 * model::kPi / 180.0)) {
      ++in_hole;
      EXPECT_EQ(filled.confidence[c], 0.0f) << "cell " << c;
      worst_in_hole = std::max(worst_in_hole, std::abs(filled.values[c] - Smooth(centre)));
    }
  }
  // The function spans 0.2-1.2 and changes by up to about 0.05 across a cell.
  EXPECT_LT(worst, 0.01) << "worst error over the cells with data everywhere";
  ASSERT_GT(in_hole, 10);
  // Across the hole (50 degrees wide) the function changes by about 0.35; the fill, a blend of
  // coarse averages around it, stays within 0.15 of it (measured 0.125).
  EXPECT_LT(worst_in_hole, 0.15) << "worst error in the hole, filled from around it";
  std::printf("worst error: %.4f with data, %.4f in the hole (%d cells)\n", worst, worst_in_hole, in_hole);
}

}  // namespace
}  // namespace svbtdf::process
