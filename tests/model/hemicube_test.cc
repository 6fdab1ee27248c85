// The hemicube: exact solid angles, cell lookup, neighbours across seams, mirroring and
// interpolation (docs/hemicube.md).
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>

#include "svbtdf/common/error.h"
#include "svbtdf/model/hemicube.h"

namespace svbtdf::model {
namespace {

Vec3 RandomUpperDirection(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  const double z = u(rng), phi = kTwoPi * u(rng), r = std::sqrt(1 - z * z);
  return {r * std::cos(phi), r * std::sin(phi), z};
}

TEST(Hemicube, SolidAnglesSumToTwoPi) {
  for (int n : {4, 8, 32}) {
    const Hemicube cube(n);
    double sum = 0;
    for (int c = 0; c < cube.num_cells(); ++c) {
      EXPECT_GT(cube.CellSolidAngle(c), 0.0);
      sum += cube.CellSolidAngle(c);
    }
    EXPECT_NEAR(sum, kTwoPi, 1e-12) << n;
    EXPECT_EQ(cube.num_cells(), 3 * n * n);
  }
}

TEST(Hemicube, SolidAngleMatchesMonteCarloAreaOfTheCell) {
  const Hemicube cube(8);
  std::mt19937_64 rng(3);
  std::vector<int> hits(cube.num_cells(), 0);
  const int samples = 2000000;
  for (int k = 0; k < samples; ++k) ++hits[cube.CellOf(RandomUpperDirection(rng))];
  for (int c = 0; c < cube.num_cells(); ++c) {
    const double expected = cube.CellSolidAngle(c) / kTwoPi * samples;
    EXPECT_NEAR(hits[c], expected, 5 * std::sqrt(expected)) << c;
  }
}

TEST(Hemicube, CellLookupIsConsistentWithCentresAndPoints) {
  const Hemicube cube(32);
  for (int c = 0; c < cube.num_cells(); ++c) {
    EXPECT_EQ(cube.CellOf(cube.CellCenter(c)), c);
    EXPECT_NEAR(cube.CellCenter(c).norm(), 1.0, 1e-12);
    EXPECT_GE(cube.CellCenter(c).z(), 0.0);
    for (double fu : {0.05, 0.5, 0.95}) {
      for (double fv : {0.05, 0.95}) EXPECT_EQ(cube.CellOf(cube.CellPoint(c, fu, fv)), c);
    }
  }
  EXPECT_THROW(Hemicube(5), common::Error);
  EXPECT_THROW(Hemicube(2), common::Error);
}

TEST(Hemicube, NeighboursAreSymmetricAndAdjacent) {
  const Hemicube cube(16);
  const double max_gap = 2.5 * (2.0 / 16);  // neighbouring centres are about one cell apart
  for (int c = 0; c < cube.num_cells(); ++c) {
    int count = 0;
    for (int nb : cube.Neighbours(c)) {
      if (nb < 0) continue;
      ++count;
      const auto back = cube.Neighbours(nb);
      EXPECT_NE(std::find(back.begin(), back.end(), c), back.end()) << c << " -> " << nb;
      EXPECT_LT((cube.CellCenter(c) - cube.CellCenter(nb)).norm(), max_gap) << c << " -> " << nb;
    }
    EXPECT_EQ(count, cube.IsHorizon(c) ? 3 : 4) << c;
  }
}

TEST(Hemicube, MirroredCellIsAnInvolutionThroughTheNormal) {
  const Hemicube cube(32);
  for (int c = 0; c < cube.num_cells(); ++c) {
    const int m = cube.MirroredCell(c);
    EXPECT_EQ(cube.MirroredCell(m), c);
    const Vec3 h = cube.CellCenter(c), mh = cube.CellCenter(m);
    EXPECT_NEAR((mh - Vec3(-h.x(), -h.y(), h.z())).norm(), 0.0, 1e-12);
  }
}

TEST(Hemicube, InterpolationWeightsArePositiveAndSumToOne) {
  const Hemicube cube(32);
  std::mt19937_64 rng(5);
  for (int k = 0; k < 20000; ++k) {
    const Vec3 d = RandomUpperDirection(rng);
    double sum = 0;
    for (const auto& [cell, w] : cube.Interpolation(d)) {
      EXPECT_GE(w, 0.0);
      EXPECT_GE(cell, 0);
      sum += w;
    }
    EXPECT_NEAR(sum, 1.0, 1e-12);
  }
  // At a cell centre the interpolation is that cell alone.
  for (int c = 0; c < cube.num_cells(); c += 37) {
    double own = 0;
    for (const auto& [cell, w] : cube.Interpolation(cube.CellCenter(c))) own += cell == c ? w : 0.0;
    EXPECT_NEAR(own, 1.0, 1e-9) << c;
  }
}

struct InterpolationErrors {
  double rms = 0, worst = 0;
};

InterpolationErrors MeasureInterpolation(int n, const std::function<double(const Vec3&)>& f) {
  const Hemicube cube(n);
  std::vector<double> values(cube.num_cells());
  for (int c = 0; c < cube.num_cells(); ++c) values[c] = f(cube.CellCenter(c));
  std::mt19937_64 rng(9);
  InterpolationErrors errors;
  int count = 0;
  for (int k = 0; k < 40000; ++k) {
    const Vec3 d = RandomUpperDirection(rng);
    if (d.z() < 0.3) continue;  // away from the horizon row, where values are extrapolated
    double value = 0;
    for (const auto& [cell, w] : cube.Interpolation(d)) value += w * values[cell];
    const double error = std::abs(value - f(d));
    errors.worst = std::max(errors.worst, error);
    errors.rms += error * error;
    ++count;
  }
  errors.rms = std::sqrt(errors.rms / count);
  return errors;
}

TEST(Hemicube, InterpolationConvergesForSmoothFunctions) {
  // Bilinear inside the faces (error ~ h^2), first order within half a cell of the seams and
  // the cube corners, where the neighbouring face's cell centres are not on the face's grid.
  const auto f = [](const Vec3& d) { return std::exp(1.5 * d.x() - 0.7 * d.y() + d.z() * d.z()); };
  const InterpolationErrors coarse = MeasureInterpolation(16, f), fine = MeasureInterpolation(32, f);
  EXPECT_LT(fine.rms, 0.4 * coarse.rms) << coarse.rms << " " << fine.rms;
  EXPECT_LT(fine.worst, 0.6 * coarse.worst) << coarse.worst << " " << fine.worst;
  EXPECT_LT(fine.rms, 3e-3);
}

TEST(Hemicube, InterpolationIsContinuousAcrossFaceSeams) {
  const Hemicube cube(32);
  std::vector<double> values(cube.num_cells());
  for (int c = 0; c < cube.num_cells(); ++c) values[c] = std::sin(3 * cube.CellCenter(c).x()) + cube.CellCenter(c).y();
  const auto interpolate = [&](const Vec3& d) {
    double v = 0;
    for (const auto& [cell, w] : cube.Interpolation(d)) v += w * values[cell];
    return v;
  };
  // Cross the top/+x seam (x = z) and the +x/+y seam (x = y) at many places, away from corners.
  for (double t = -0.8; t <= 0.8; t += 0.05) {
    const Vec3 top_seam = Vec3(1.0, t, 1.0).normalized();
    const Vec3 eps_in = Vec3(1.0 - 1e-9, t, 1.0).normalized(), eps_out = Vec3(1.0 + 1e-9, t, 1.0).normalized();
    EXPECT_NEAR(interpolate(eps_in), interpolate(eps_out), 1e-6) << t;
    (void)top_seam;
    const double z = 0.4 + 0.25 * t;
    const Vec3 side_in = Vec3(1.0, 1.0 - 1e-9, z).normalized(), side_out = Vec3(1.0 - 1e-9, 1.0, z).normalized();
    EXPECT_NEAR(interpolate(side_in), interpolate(side_out), 1e-6) << t;
  }
}

}  // namespace
}  // namespace svbtdf::model
