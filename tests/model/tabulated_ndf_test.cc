// The tabulated hemicube NDF: normalisation, fidelity to the analytic NDF it was sampled from,
// its Smith masking and its visible-normal sampler.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "chi_square.h"
#include "svbtdf/common/error.h"
#include "svbtdf/model/ggx.h"
#include "svbtdf/model/tabulated_ndf.h"

namespace svbtdf::model {
namespace {

// Integral of f over the upper hemisphere on a fine (cos theta, phi) grid: a quadrature unrelated
// to the hemicube's.
double IntegrateHemisphere(const std::function<double(const Vec3&)>& f, int n = 800) {
  double sum = 0;
  for (int a = 0; a < n; ++a) {
    const double z = (a + 0.5) / n, r = std::sqrt(1 - z * z);
    for (int b = 0; b < 2 * n; ++b) {
      const double phi = kPi * (b + 0.5) / n;
      sum += f(Vec3(r * std::cos(phi), r * std::sin(phi), z));
    }
  }
  return sum * (1.0 / n) * (kPi / n);
}

TabulatedNdf TableOfGgx(double alpha, int resolution = 32) {
  TabulatedNdf table(Hemicube(resolution), GgxNdf(alpha, 0.7 * alpha));
  table.Normalize();
  return table;
}

TEST(TabulatedNdf, NormalisesToOneUnderAnIndependentEstimate) {
  // Importance sampling with the analytic GGX the table came from (pdf = D_ggx h.z, drawn by its
  // visible-normal sampler seen from the normal): an estimate independent of the hemicube's
  // quadrature, with a standard error near 5e-5 at 10^6 samples.
  for (double alpha : {0.2, 0.4, 0.8}) {
    const GgxNdf ggx(alpha, 0.7 * alpha);
    const TabulatedNdf table = TableOfGgx(alpha);
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(0, 1);
    constexpr int kSamples = 1000000;
    double sum = 0, sum2 = 0;
    for (int k = 0; k < kSamples; ++k) {
      const NormalSample s = ggx.SampleVisibleNormal(Vec3::UnitZ(), Vec2(u(rng), u(rng)));
      const double ratio = table.D(s.h) * s.h.z() / s.pdf;
      sum += ratio;
      sum2 += ratio * ratio;
    }
    const double mean = sum / kSamples;
    const double standard_error = std::sqrt((sum2 / kSamples - mean * mean) / kSamples);
    EXPECT_NEAR(mean, 1.0, std::max(1e-3, 4 * standard_error)) << alpha;
    EXPECT_LT(standard_error, 2e-4);
    EXPECT_NEAR(table.ProjectedIntegral(), 1.0, 1e-12);
  }
}

TEST(TabulatedNdf, ReproducesTheAnalyticNdfItWasSampledFrom) {
  const GgxNdf ggx(0.3, 0.21);
  const TabulatedNdf table = TableOfGgx(0.3);
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<double> errors;
  for (int k = 0; k < 5000; ++k) {
    const Vec3 h = SphericalDirection(0.6 * u(rng), kTwoPi * u(rng));  // where D is not negligible
    errors.push_back(std::abs(table.D(h) / ggx.D(h) - 1.0));
  }
  std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
  EXPECT_LT(errors[errors.size() / 2], 0.05);
}

TEST(TabulatedNdf, MaskingIsBoundedAndCloseToTheAnalyticSmithTerm) {
  const GgxNdf ggx(0.3, 0.21);
  const TabulatedNdf table = TableOfGgx(0.3);
  for (double theta : {0.0, 0.5, 1.0, 1.3}) {
    const Vec3 v = SphericalDirection(theta, 0.4);
    const Vec3 h = Vec3::UnitZ();
    const double g = table.G1(v, h);
    EXPECT_GE(g, 0.0);
    EXPECT_LE(g, 1.0);
    EXPECT_NEAR(g, ggx.G1(v, h), 0.02) << theta;
    // Projected-area inequality: the visible projected area does not exceed the macro surface's.
    const double visible = IntegrateHemisphere([&](const Vec3& m) { return table.G1(v, m) * std::max(0.0, v.dot(m)) * table.D(m); }, 400);
    EXPECT_LE(visible, v.z() * (1 + 2e-3)) << theta;
  }
  EXPECT_EQ(table.G1(SphericalDirection(1.2, 0.0), SphericalDirection(0.5, kPi)), 0.0);
}

TEST(TabulatedNdf, SamplerMatchesItsPdfAndWeightsAreAtMostOne) {
  const TabulatedNdf table = TableOfGgx(0.35, 16);
  const Vec3 v = SphericalDirection(0.7, 0.3);
  // Histogram over the hemicube's own cells: expected counts from the pdf integrated per cell.
  const Hemicube& grid = table.grid();
  std::vector<double> expected(grid.num_cells(), 0.0);
  constexpr int kSub = 6;
  for (int c = 0; c < grid.num_cells(); ++c) {
    for (int a = 0; a < kSub; ++a) {
      for (int b = 0; b < kSub; ++b) {
        const Vec3 h = grid.CellPoint(c, (a + 0.5) / kSub, (b + 0.5) / kSub);
        const double dominant = std::max({std::abs(h.x()), std::abs(h.y()), h.z()});
        expected[c] += table.VisibleNormalPdf(v, h) * std::pow(dominant, 3);
      }
    }
  }
  double expected_total = 0;
  for (int c = 0; c < grid.num_cells(); ++c) {
    double face_weight = 0;
    for (int a = 0; a < kSub; ++a) {
      for (int b = 0; b < kSub; ++b) {
        const Vec3 h = grid.CellPoint(c, (a + 0.5) / kSub, (b + 0.5) / kSub);
        face_weight += std::pow(std::max({std::abs(h.x()), std::abs(h.y()), h.z()}), 3);
      }
    }
    expected[c] *= grid.CellSolidAngle(c) / face_weight;
    expected_total += expected[c];
  }
  EXPECT_NEAR(expected_total, 1.0, 5e-3);  // the pdf integrates to 1
  constexpr int kSamples = 100000;
  std::vector<double> observed(grid.num_cells(), 0.0);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  for (int k = 0; k < kSamples; ++k) {
    const NormalSample s = table.SampleVisibleNormal(v, Vec2(u(rng), u(rng)));
    ASSERT_GT(s.pdf, 0.0);
    EXPECT_NEAR(s.pdf, table.VisibleNormalPdf(v, s.h), 1e-12 * s.pdf);
    EXPECT_LE(s.weight, 1.0 + 1e-9);
    ++observed[grid.CellOf(s.h)];
  }
  // Pearson chi-square over cells with enough expected samples, the rest pooled.
  std::vector<double> expected_counts(grid.num_cells());
  for (int c = 0; c < grid.num_cells(); ++c) expected_counts[c] = expected[c] / expected_total * kSamples;
  const svbtdf::testing::ChiSquareStatistic statistic = svbtdf::testing::PooledChiSquare(observed, expected_counts);
  EXPECT_LT(statistic.chi2, svbtdf::testing::ChiSquareBound(statistic.bins)) << "bins " << statistic.bins;
  EXPECT_GT(statistic.bins, 50);
}

TEST(TabulatedNdf, RejectsTablesOfTheWrongSize) {
  EXPECT_THROW(TabulatedNdf(Hemicube(8), std::vector<double>(10, 0.0)), common::Error);
  std::vector<double> bad(Hemicube(8).num_cells(), 0.0);
  bad[3] = std::nan("");
  EXPECT_THROW(TabulatedNdf(Hemicube(8), bad), common::Error);
}

}  // namespace
}  // namespace svbtdf::model
