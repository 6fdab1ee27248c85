// model::TabulatedNdfBlend: D is the weighted sum of its tables, normalised when they are and
// the weights sum to 1, clamped at 0 where negative weights undershoot; its visible-normal
// sampler follows the density it reports (chi-square), also with a negative weight.
#include "svbtdf/model/ndf_blend.h"

#include <gtest/gtest.h>

#include <random>

#include "sampling_check.h"
#include "svbtdf/common/error.h"
#include "svbtdf/model/ggx.h"

namespace svbtdf::model {
namespace {

std::vector<TabulatedNdf> Tables() {
  const Hemicube grid(32);
  std::vector<TabulatedNdf> tables;
  for (const GgxNdf& ggx : {GgxNdf(0.15, 0.15), GgxNdf(0.45, 0.25), GgxNdf(0.3, 0.6)}) {
    tables.emplace_back(grid, ggx);
    tables.back().Normalize();
  }
  return tables;
}

TEST(TabulatedNdfBlend, DIsTheWeightedSumAndStaysNormalised) {
  const std::vector<TabulatedNdf> tables = Tables();
  TabulatedNdfBlend blend;
  const double weights[3] = {0.5, 0.3, 0.2};
  for (int j = 0; j < 3; ++j) blend.Add(tables[j], weights[j]);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0, 1);
  for (int k = 0; k < 200; ++k) {
    const Vec3 h = SphericalDirection(std::acos(u(rng)), kTwoPi * u(rng));
    double want = 0;
    for (int j = 0; j < 3; ++j) want += weights[j] * tables[j].D(h);
    EXPECT_NEAR(blend.D(h), want, 1e-12 * want);
  }
  EXPECT_EQ(blend.D(Vec3(0, 0, -1)), 0.0);
  // The integral of D h.z, by a quadrature independent of the tables' own (8 x 8 per cell of a
  // finer hemicube): the tables are normalised, so the blend is within the quadratures' gap.
  const Hemicube fine(48);
  double integral = 0;
  for (double cell : testing::CellIntegrals(fine, [&](const Vec3& h) { return blend.D(h) * h.z(); })) integral += cell;
  EXPECT_NEAR(integral, 1.0, 5e-3);
}

TEST(TabulatedNdfBlend, ANegativeWeightIsClampedAtZero) {
  const std::vector<TabulatedNdf> tables = Tables();
  TabulatedNdfBlend blend;
  blend.Add(tables[0], 1.6);  // sharp
  blend.Add(tables[1], -0.6);  // wide: its tails exceed the sharp lobe's
  const Vec3 tail = SphericalDirection(1.2, 0.3);
  ASSERT_LT(1.6 * tables[0].D(tail) - 0.6 * tables[1].D(tail), 0.0);
  EXPECT_EQ(blend.D(tail), 0.0);
  EXPECT_GT(blend.D(Vec3::UnitZ()), tables[0].D(Vec3::UnitZ()));
}

TEST(TabulatedNdfBlend, SamplesItsVisibleNormalsWithTheDensityItReports) {
  const std::vector<TabulatedNdf> tables = Tables();
  TabulatedNdfBlend positive, with_negative;
  positive.Add(tables[0], 0.2);
  positive.Add(tables[1], 0.5);
  positive.Add(tables[2], 0.3);
  with_negative.Add(tables[1], 1.3);
  with_negative.Add(tables[2], -0.3);
  for (const TabulatedNdfBlend* blend : {&positive, &with_negative}) {
    for (const Vec3& v : {Vec3(Vec3::UnitZ()), SphericalDirection(0.7, 1.0), SphericalDirection(1.3, 4.0)}) {
      const testing::SamplerCheck check = testing::CheckSampler(*blend, v, 200000, 11);
      const std::string where = std::string(blend == &positive ? "positive" : "negative weight") + " v.z " + std::to_string(v.z());
      EXPECT_TRUE(check.Passes()) << where << ": chi2 " << check.chi2 << " over " << check.bins;
      EXPECT_NEAR(check.pdf_integral, 1.0, 1e-2) << where;
      EXPECT_LT(check.max_pdf_mismatch, 1e-9) << where;
      EXPECT_LT(check.max_weight_mismatch, 1e-9) << where;
      // Non-negative weights: exactly the blend's visible normals, whose weight is min(1, A/v.z).
      if (blend == &positive) {
        EXPECT_LE(check.max_weight, 1.0 + 1e-9) << where;
      }
    }
  }
}

TEST(TabulatedNdfBlend, RefusesWhatItCannotBlend) {
  const std::vector<TabulatedNdf> tables = Tables();
  TabulatedNdfBlend blend;
  EXPECT_THROW(blend.Add(tables[0], std::nan("")), common::Error);
  blend.Add(tables[0], 0.0);
  EXPECT_EQ(blend.size(), 0);  // zero weights are skipped
  for (int k = 0; k < TabulatedNdfBlend::kMaxComponents; ++k) blend.Add(tables[k % 3], 1.0 / TabulatedNdfBlend::kMaxComponents);
  EXPECT_THROW(blend.Add(tables[0], 0.1), common::Error);
  TabulatedNdfBlend mixed;
  const TabulatedNdf coarse(Hemicube(8), GgxNdf(0.3));
  mixed.Add(tables[0], 0.5);
  EXPECT_THROW(mixed.Add(coarse, 0.5), common::Error);
}

}  // namespace
}  // namespace svbtdf::model
