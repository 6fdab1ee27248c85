// The per-texel GGX lobe fit: known lobes recovered from their tabulation, a lobe of another
// shape reported as a poor fit, and a material's texels fitted.

#include "svbtdf/export/lobe_fit.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

#include "small_material.h"
#include "svbtdf/model/beckmann.h"
#include "svbtdf/model/ggx.h"

namespace svbtdf::exporter {
namespace {

// D of `ndf` turned by `azimuth` about z, at every cell centre.
std::vector<double> Tabulate(const model::Hemicube& grid, const model::Ndf& ndf, double azimuth) {
  const Eigen::AngleAxisd unrotate(-azimuth, model::Vec3::UnitZ());
  std::vector<double> d(grid.num_cells());
  for (int c = 0; c < grid.num_cells(); ++c) d[c] = ndf.D(unrotate * grid.CellCenter(c));
  return d;
}

double AzimuthDistance(double a, double b) {
  const double d = std::fmod(std::abs(a - b), std::numbers::pi);
  return std::min(d, std::numbers::pi - d);
}

struct KnownLobe {
  double alpha_x, alpha_y, azimuth;
};

class RecoversTabulatedGgx : public ::testing::TestWithParam<KnownLobe> {};

TEST_P(RecoversTabulatedGgx, WithinTwoPercentAndAHundredthOfARadian) {
  const KnownLobe truth = GetParam();
  const model::Hemicube grid(32);
  const LobeFit fit = GgxLobeFitter(grid).Fit(Tabulate(grid, model::GgxNdf(truth.alpha_x, truth.alpha_y), truth.azimuth));
  EXPECT_NEAR(fit.lobe.alpha_x / truth.alpha_x, 1.0, 0.02);
  EXPECT_NEAR(fit.lobe.alpha_y / truth.alpha_y, 1.0, 0.02);
  if (truth.alpha_x != truth.alpha_y) {
    EXPECT_LT(AzimuthDistance(fit.lobe.azimuth, truth.azimuth), 0.01);
  }
  EXPECT_LT(fit.relative_error, 0.01);
  EXPECT_GE(fit.lobe.azimuth, -std::numbers::pi / 2);
  EXPECT_LT(fit.lobe.azimuth, std::numbers::pi / 2);
}

INSTANTIATE_TEST_SUITE_P(Lobes, RecoversTabulatedGgx,
                         ::testing::Values(KnownLobe{0.3, 0.12, 0.6}, KnownLobe{0.5, 0.2, -1.2}, KnownLobe{0.2, 0.2, 0.0},
                                           KnownLobe{0.15, 0.08, 1.5}, KnownLobe{0.8, 0.4, 0.3}));

TEST(GgxLobeFitter, ScaleOfTheTableDoesNotMatter) {
  const model::Hemicube grid(32);
  std::vector<double> d = Tabulate(grid, model::GgxNdf(0.3, 0.12), 0.6);
  const LobeFit unit = GgxLobeFitter(grid).Fit(d);
  for (double& value : d) value *= 37.0;
  const LobeFit scaled = GgxLobeFitter(grid).Fit(d);
  EXPECT_NEAR(unit.lobe.alpha_x, scaled.lobe.alpha_x, 1e-6);
  EXPECT_NEAR(unit.relative_error, scaled.relative_error, 1e-6);
}

TEST(GgxLobeFitter, ReportsALobeOfAnotherShapeAsAPoorFit) {
  // Beckmann's tails fall much faster than GGX's: an ellipse of GGX cannot follow them.
  const model::Hemicube grid(32);
  const LobeFit beckmann = GgxLobeFitter(grid).Fit(Tabulate(grid, model::BeckmannNdf(0.3, 0.3), 0.0));
  EXPECT_GT(beckmann.relative_error, 0.05);
  // Two lobes side by side are no ellipse at all.
  std::vector<double> pair = Tabulate(grid, model::GgxNdf(0.05, 0.05), 0.0);
  const Eigen::AngleAxisd tilt(0.3, model::Vec3::UnitY());
  const model::GgxNdf narrow(0.05, 0.05);
  for (int c = 0; c < grid.num_cells(); ++c) pair[c] += narrow.D(tilt * grid.CellCenter(c));
  EXPECT_GT(GgxLobeFitter(grid).Fit(pair).relative_error, 0.3);
}

TEST(FitMaterialLobes, FitsEveryTexelOfAMaterial) {
  // SmallMaterial's one representative is GGX (0.25, 0.18) tabulated at resolution 16.
  const fit::Material material = SmallMaterial(4, 3);
  const MaterialLobes lobes = FitMaterialLobes(material, 2);
  ASSERT_EQ(lobes.alpha_x.width, 4);
  ASSERT_EQ(lobes.alpha_x.height, 3);
  EXPECT_FALSE(lobes.exact);
  for (int y = 0; y < 3; ++y) {
    for (int x = 0; x < 4; ++x) {
      EXPECT_NEAR(lobes.alpha_x.at(x, y), 0.25, 0.25 * 0.05);
      EXPECT_NEAR(lobes.alpha_y.at(x, y), 0.18, 0.18 * 0.05);
      EXPECT_LT(AzimuthDistance(lobes.azimuth.at(x, y), 0.0), 0.02);
      EXPECT_LT(lobes.relative_error.at(x, y), 0.05);
    }
  }
}

TEST(FitMaterialLobes, CrossedLobesAreNoEllipseAndTheErrorMapSaysWhere) {
  // Inside a grid cell the lobe is GGX (0.40, 0.05); on a line it is turned a quarter; beside a
  // line the two blend half and half, a cross.
  const fit::Material material = GridSheetLikeMaterial(16, 8);
  const MaterialLobes lobes = FitMaterialLobes(material, 2);
  EXPECT_NEAR(lobes.alpha_x.at(4, 4), 0.40, 0.40 * 0.02);  // a cell's centre
  EXPECT_NEAR(lobes.alpha_y.at(4, 4), 0.05, 0.05 * 0.02);
  EXPECT_LT(AzimuthDistance(lobes.azimuth.at(4, 4), 0.0), 0.01);
  EXPECT_LT(lobes.relative_error.at(4, 4), 0.01);
  EXPECT_LT(AzimuthDistance(lobes.azimuth.at(8, 4), std::numbers::pi / 2), 0.01);  // on a line: turned
  EXPECT_LT(lobes.relative_error.at(8, 4), 0.01);
  EXPECT_GT(lobes.relative_error.at(7, 4), 0.3);  // beside it: the cross
  const ErrorDistribution d = Distribution(lobes.relative_error);
  EXPECT_LT(d.median, 0.01);
  EXPECT_GT(d.max, 0.3);
}

TEST(FitMaterialLobes, AWalterGgxMaterialsLobesAreExportedAsTheyAre) {
  fit::Material material = SmallMaterial(3, 2);
  material.model = fit::MaterialModel::kWalterGgx;
  material.baseline_alpha_x = common::FloatImage(3, 2, 1, 0.3f);
  material.baseline_alpha_y = common::FloatImage(3, 2, 1, 0.1f);
  material.baseline_azimuth = common::FloatImage(3, 2, 1, 0.7f);
  const MaterialLobes lobes = FitMaterialLobes(material, 1);
  EXPECT_TRUE(lobes.exact);
  EXPECT_EQ(lobes.alpha_x.at(2, 1), 0.3f);
  EXPECT_EQ(lobes.alpha_y.at(2, 1), 0.1f);
  EXPECT_EQ(lobes.azimuth.at(2, 1), 0.7f);
  EXPECT_EQ(Distribution(lobes.relative_error).max, 0.0);
}

TEST(Distribution, MedianNinetiethPercentileAndMaximum) {
  common::FloatImage map(10, 1, 1);
  for (int x = 0; x < 10; ++x) map.at(x, 0) = static_cast<float>(x + 1);
  const ErrorDistribution d = Distribution(map);
  EXPECT_EQ(d.median, 6.0);
  EXPECT_EQ(d.p90, 10.0);
  EXPECT_EQ(d.max, 10.0);
}

}  // namespace
}  // namespace svbtdf::exporter
