// report/texel_inspection.h: the grid of inspected texels, its size budget, and the spherical
// Gaussian each texel's transmission lobe gets for the page's live view.
#include "svbtdf/report/texel_inspection.h"

#include <gtest/gtest.h>

#include "small_material.h"

namespace svbtdf::report {
namespace {

TEST(TexelInspection, GridSpreadsEvenlyAndKeepsWithinTheBudget) {
  const TexelGrid grid = MakeTexelGrid(600, 300, 64);
  EXPECT_EQ(grid.cols, 64);
  EXPECT_EQ(grid.rows, 64);
  EXPECT_EQ(grid.x.front(), 4);
  EXPECT_EQ(grid.x.back(), 595);
  const TexelGrid small = MakeTexelGrid(3, 2, 64);
  EXPECT_EQ(small.x, std::vector<int>({0, 1, 2}));
  EXPECT_EQ(small.y, std::vector<int>({0, 1}));
  EXPECT_EQ(InspectionGridSide(600, 600, 576, 64, 400000), 26);  // 26^2 x 576 <= 400000
  EXPECT_EQ(InspectionGridSide(32, 32, 36, 64, 400000), 32);
  EXPECT_EQ(InspectionGridSide(600, 600, 0, 64, 400000), 64);
}

TEST(TexelInspection, AHeadOnLobeLiesStraightThroughAndNarrowsWithRoughness) {
  double previous_sharpness = 1e300;
  for (const double roughness : {0.1, 0.25, 0.5}) {
    fit::Material m = SmallMaterial();
    model::TabulatedNdf ndf(model::Hemicube(16), model::GgxNdf(roughness, roughness));
    ndf.Normalize();
    m.representative_ln_d = {ndf.ln_d()};
    const fit::MaterialEvaluator evaluator(m);
    const TexelLobe lobe = FitTexelLobe(evaluator.Texel(1, 1), model::Vec3::UnitZ());
    // Isotropic and head-on: the lobe points straight through, -z.
    EXPECT_NEAR(lobe.lobe.axis.z(), -1.0, 1e-3) << roughness;
    EXPECT_LT(lobe.lobe.sharpness, previous_sharpness) << roughness;
    previous_sharpness = lobe.lobe.sharpness;
    EXPECT_LT(lobe.relative_l2, 0.35) << roughness;
    // Round: the sharpnesses along and across differ little; grey like k_s; energy below 1.
    EXPECT_GT(lobe.sharpness_major / lobe.sharpness_minor, 0.8) << roughness;
    EXPECT_NEAR(lobe.energy_rgb[0], lobe.energy_rgb[2], 1e-9 + 1e-6 * lobe.energy_rgb[0]);
    EXPECT_GT(lobe.energy_rgb[0], 0.1) << roughness;
    EXPECT_LT(lobe.energy_rgb[0], 1.0) << roughness;
  }
}

TEST(TexelInspection, AnAnisotropicLobeIsWidestAlongItsRougherAxis) {
  for (const bool along_x : {true, false}) {
    fit::Material m = SmallMaterial();
    model::TabulatedNdf ndf(model::Hemicube(16), along_x ? model::GgxNdf(0.4, 0.12) : model::GgxNdf(0.12, 0.4));
    ndf.Normalize();
    m.representative_ln_d = {ndf.ln_d()};
    const fit::MaterialEvaluator evaluator(m);
    const TexelLobe lobe = FitTexelLobe(evaluator.Texel(1, 1), model::Vec3::UnitZ());
    EXPECT_GT(std::abs(along_x ? lobe.major.x() : lobe.major.y()), 0.95) << along_x;
    EXPECT_LT(lobe.sharpness_major, 0.5 * lobe.sharpness_minor) << along_x;
    EXPECT_NEAR(lobe.sharpness_major * lobe.sharpness_minor, lobe.lobe.sharpness * lobe.lobe.sharpness,
                1e-9 * lobe.lobe.sharpness * lobe.lobe.sharpness);
  }
}

TEST(TexelInspection, ALobeBeyondTheHorizonIsLeftEmptyNotAnError) {
  const fit::Material m = SmallMaterial();
  const fit::MaterialEvaluator evaluator(m);
  // A view grazing the sample: its lobe lies almost wholly above the horizon.
  const TexelLobe lobe = FitTexelLobe(evaluator.Texel(0, 0), model::Vec3(0.9999, 0, 0.0141).normalized());
  EXPECT_GE(lobe.energy_rgb[0], 0.0);
}

TEST(TexelInspection, ASlantedViewShiftsTheLobe) {
  const fit::Material m = SmallMaterial();
  const fit::MaterialEvaluator evaluator(m);
  const std::vector<model::Vec3> views = LobeViews();
  ASSERT_EQ(views.size(), 5u);
  const TexelLobe slanted = FitTexelLobe(evaluator.Texel(0, 0), views[1]);  // 30 degrees toward +x
  // The light comes from the other side, below: i.x < 0, i.z < 0.
  EXPECT_LT(slanted.lobe.axis.x(), -0.2);
  EXPECT_LT(slanted.lobe.axis.z(), -0.5);
}

TEST(TexelInspection, LobeDataHoldsEveryGridTexelsRecords) {
  const fit::Material m = SmallMaterial(4, 3);
  const nlohmann::json lobes = LobeData(m, MakeTexelGrid(4, 3, 2), 1);
  EXPECT_EQ(lobes["cols"], 2);
  EXPECT_EQ(lobes["rows"], 2);
  EXPECT_EQ(lobes["stride"], 58);  // 5 views x 11 + rho_d
  // base64 of 4 texels x 58 float32.
  EXPECT_EQ(lobes["data"].get<std::string>().size(), (4 * 58 * 4 + 2) / 3 * 4);
}

}  // namespace
}  // namespace svbtdf::report
