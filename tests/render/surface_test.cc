// render::Surface: a fitted material's texels as renderers see them agree with the evaluator
// `svbtdf compare` scores (exactly for a representative, within a stated tolerance for blends),
// sample what their pdf says, and a truth surface is the truth the simulator rendered.
#include "svbtdf/render/surface.h"

#include <gtest/gtest.h>

#include <cmath>

#include "sampling_check.h"
#include "simulated_truths.h"
#include "small_material.h"
#include "svbtdf/common/error.h"
#include "svbtdf/model/ggx.h"
#include "temp_folder.h"

namespace svbtdf::render {
namespace {
namespace fs = std::filesystem;
using model::Vec3;

Vec3 Direction(double theta_deg, double phi_deg) {
  return model::SphericalDirection(theta_deg * model::kPi / 180, phi_deg * model::kPi / 180);
}

// Six texels: three representatives (GGX tables of unlike roughness and scale) on texels 0-2,
// texel 3 a blend of all three, texel 4 an affine blend with a negative weight, texel 5 one whose
// terms nearly cancel (clamping its negative part adds several times the blend's mass).
fit::Material BlendedMaterial() {
  fit::Material m = SmallMaterial(6, 1);
  m.ndf_resolution = 32;  // the fit's default (the paper's)
  const model::Hemicube grid(m.ndf_resolution);
  m.representative_texels = {0, 1, 2};
  m.representative_ln_d.clear();
  for (const model::GgxNdf& ggx : {model::GgxNdf(0.12), model::GgxNdf(0.4, 0.22), model::GgxNdf(0.3, 0.55)}) {
    model::TabulatedNdf table(grid, ggx);
    table.Normalize();
    m.representative_ln_d.push_back(table.ln_d());
  }
  const float k_s[6] = {0.8f, 1.2f, 0.5f, 0.9f, 1.0f, 1.1f};
  const float alpha[6] = {0.2f, 0.6f, 0.9f, 0.5f, 0.4f, 0.5f};
  for (int x = 0; x < 6; ++x) {
    for (int c = 0; c < 3; ++c) m.k_s.at(x, 0, c) = k_s[x] * (1.0f - 0.1f * c);
    m.alpha.at(x, 0) = alpha[x];
  }
  m.weight_index = common::FloatImage(6, 1, 3);
  m.weight_value = common::FloatImage(6, 1, 3);
  const float weights[6][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0.5f, 0.3f, 0.2f}, {0.1f, 1.2f, -0.3f}, {-2.0f, 3.0f, 0.0f}};
  for (int x = 0; x < 6; ++x) {
    for (int k = 0; k < 3; ++k) {
      m.weight_index.at(x, 0, k) = static_cast<float>(k);
      m.weight_value.at(x, 0, k) = weights[x][k];
    }
  }
  return m;
}

// sqrt(sum (a - b)^2 / sum b^2) of the luminance over lights on a grid behind the sample, for
// viewers at 0, 35 and 65 degrees.
double RelativeL2(const model::Bsdf& bsdf, const fit::TexelBtdf& reference) {
  double error = 0, norm = 0;
  for (const Vec3& wo : {Direction(0, 0), Direction(35, 40), Direction(65, 190)}) {
    for (double theta = 2.5; theta < 88; theta += 5) {
      for (double phi = 0; phi < 360; phi += 15) {
        const Vec3 wi = model::FlipZ(Direction(theta, phi));
        const double a = model::Luminance(bsdf.Eval(wi, wo)), b = model::Luminance(reference.Evaluate(wi, wo));
        error += (a - b) * (a - b);
        norm += b * b;
      }
    }
  }
  return std::sqrt(error / norm);
}

TEST(MaterialSurface, RepresentativesAreExactlyTheEvaluatorsAndBlendsAgreeWithItsTolerance) {
  const fit::Material material = BlendedMaterial();
  const MaterialSurface surface(material, 0.05, 0.01, "test material");
  const fit::MaterialEvaluator evaluator(material);
  BsdfScratch scratch;
  for (int x = 0; x < 3; ++x) {
    EXPECT_LT(RelativeL2(surface.At(x, 0, scratch), evaluator.Texel(x, 0)), 1e-6) << "representative " << x;
  }
  // A blend is summed after interpolating its tables, the evaluator before: they differ between
  // hemicube cell centres only (measured 0.44% and 0.27% at resolution 32; 1.4% and 1.0% at 16).
  // Texel 5's terms nearly cancel: clamping its negative part adds 2.6 times its mass, and where D
  // crosses zero the two interpolations differ most (measured 8.1%; 40x before the surface
  // normalised the clamped blend).
  for (int x = 3; x < 6; ++x) {
    const double error = RelativeL2(surface.At(x, 0, scratch), evaluator.Texel(x, 0));
    EXPECT_LT(error, x == 5 ? 0.1 : 0.01) << "blended texel " << x;
    std::printf("blended texel %d: relative L2 %.5f against MaterialEvaluator\n", x, error);
  }
}

TEST(MaterialSurface, BlendedTexelsSampleWhatTheirPdfSays) {
  const fit::Material material = BlendedMaterial();
  const MaterialSurface surface(material, 0.05, 0.01, "test material");
  BsdfScratch scratch;
  for (int x : {3, 4, 5}) {
    const model::Bsdf& bsdf = surface.At(x, 0, scratch);
    for (const Vec3& wo : {Direction(0, 0), Direction(50, 120), model::FlipZ(Direction(30, 10))}) {
      const model::testing::BsdfSamplerCheck c = model::testing::CheckBsdf(bsdf, wo, 200000, 21);
      const std::string where = "texel " + std::to_string(x) + " wo.z " + std::to_string(wo.z());
      EXPECT_TRUE(c.Passes()) << where << ": chi2 " << c.chi2 << " over " << c.bins;
      EXPECT_LT(c.max_pdf_mismatch, 1e-9) << where;
      EXPECT_LT(c.max_weight_mismatch, 1e-9) << where;
      EXPECT_LE(c.mean_weight, 1.0 + 4 * c.weight_standard_error) << where << ": more energy out than in";
    }
  }
}

TEST(MaterialSurface, ABaselineTexelIsTheEvaluatorsWalterTexel) {
  fit::Material m = SmallMaterial(3, 2);
  m.model = fit::MaterialModel::kWalterGgx;
  m.baseline_alpha_x = common::FloatImage(3, 2, 1, 0.3f);
  m.baseline_alpha_y = common::FloatImage(3, 2, 1, 0.15f);
  m.baseline_azimuth = common::FloatImage(3, 2, 1, 0.4f);
  const MaterialSurface surface(m, 0.03, 0.02, "baseline");
  BsdfScratch scratch;
  EXPECT_LT(RelativeL2(surface.At(1, 1, scratch), fit::MaterialEvaluator(m).Texel(1, 1)), 1e-9);
  EXPECT_EQ(surface.description(), "fitted walter-ggx material");
}

TEST(MaterialSurface, ASlabTexelIsTheEvaluatorsSlabTexel) {
  fit::Material m = SmallMaterial(3, 2);
  m.model = fit::MaterialModel::kSlab;
  m.slab_entry_alpha_x = common::FloatImage(3, 2, 1, 0.3f);
  m.slab_entry_alpha_y = common::FloatImage(3, 2, 1, 0.1f);
  m.slab_entry_azimuth = common::FloatImage(3, 2, 1, 0.4f);  // turned: the Ellipsoid NDF
  m.slab_exit_alpha_x = m.slab_exit_alpha_y = common::FloatImage(3, 2, 1, 0.12f);
  m.slab_exit_azimuth = common::FloatImage(3, 2, 1, 0.0f);
  m.slab_entry_roughness_se = m.slab_exit_roughness_se = common::FloatImage(3, 2, 1, 0.01f);
  m.slab_internal_reflection = common::FloatImage(3, 2, 1, 1.2f);
  const MaterialSurface surface(m, 0.03, 0.02, "slab");
  BsdfScratch scratch;
  EXPECT_LT(RelativeL2(surface.At(1, 1, scratch), fit::MaterialEvaluator(m).Texel(1, 1)), 1e-9);
  // With the longer internal paths (version 6): the renderer widens the same sides, and they add
  // light.
  const fit::Material without = m;
  m.slab_longer_paths = common::FloatImage(3, 2, 1, 0.7f);
  const MaterialSurface longer(m, 0.03, 0.02, "slab");
  EXPECT_LT(RelativeL2(longer.At(1, 1, scratch), fit::MaterialEvaluator(m).Texel(1, 1)), 1e-9);
  EXPECT_GT(RelativeL2(longer.At(1, 1, scratch), fit::MaterialEvaluator(without).Texel(1, 1)), 1e-3);
  EXPECT_EQ(surface.description(), "fitted slab material");
}

// A material whose one representative is an anisotropic GGX lobe turned by 0.6 rad, tabulated.
fit::Material TurnedLobeMaterial(const fit::BaselineLobe& lobe) {
  fit::Material m = SmallMaterial(3, 2);
  m.ndf_resolution = 32;
  model::TabulatedNdf table(model::Hemicube(32), fit::BaselineLnD(model::Hemicube(32), lobe));
  table.Normalize();
  m.representative_ln_d = {table.ln_d()};
  return m;
}

TEST(LobeSurface, ATurnedLobeIsTheMaterialsTabulatedTexel) {
  const fit::BaselineLobe lobe{0.35, 0.12, 0.6};
  const fit::Material material = TurnedLobeMaterial(lobe);
  const auto map = [&](double value) { return common::FloatImage(3, 2, 1, static_cast<float>(value)); };
  const LobeSurface surface(material, map(lobe.alpha_x), map(lobe.alpha_y), map(lobe.azimuth), 0.03, 0.02, "lobes");
  BsdfScratch scratch;
  const fit::TexelBtdf reference = fit::MaterialEvaluator(material).Texel(1, 1);
  // The table is the lobe at cell centres, interpolated: they agree to the table's resolution.
  EXPECT_LT(RelativeL2(surface.At(1, 1, scratch), reference), 0.05);
  // The same lobe turned the other way is far off: the azimuth's sign is right.
  const LobeSurface mirrored(material, map(lobe.alpha_x), map(lobe.alpha_y), map(-lobe.azimuth), 0.03, 0.02, "lobes");
  EXPECT_GT(RelativeL2(mirrored.At(1, 1, scratch), reference), 0.3);
  for (const Vec3& wo : {Direction(0, 0), Direction(50, 120)}) {
    const model::testing::BsdfSamplerCheck c = model::testing::CheckBsdf(surface.At(1, 1, scratch), wo, 200000, 22);
    EXPECT_TRUE(c.Passes()) << "chi2 " << c.chi2 << " over " << c.bins;
  }
}

TEST(LobeSurface, RefusesLobeMapsOfAnotherSize) {
  const fit::Material material = SmallMaterial(3, 2);
  const common::FloatImage wrong(2, 2, 1, 0.2f), right(3, 2, 1, 0.2f);
  EXPECT_THROW(LobeSurface(material, wrong, right, right, 0.03, 0.02, "lobes"), common::Error);
}

TEST(LoadSurface, ReadsMaterialsAndNamesWhatIsMissing) {
  const testing::TempFolder folder;
  fit::Material m = SmallMaterial();
  fit::WriteMaterial(folder / "unsized", m);
  m.width_m = 0.03;
  m.height_m = 0.02;
  fit::WriteMaterial(folder / "sized", m);
  const LoadedSurface sized = LoadSurface(folder / "sized");
  EXPECT_DOUBLE_EQ(sized.surface().width_m(), 0.03);
  EXPECT_EQ(sized.surface().texels_x(), 3);
  try {
    LoadSurface(folder / "unsized");
    FAIL() << "a material without a size was rendered";
  } catch (const common::Error& e) {
    EXPECT_NE(std::string(e.what()).find("--sample-size"), std::string::npos) << e.what();
  }
  EXPECT_DOUBLE_EQ(LoadSurface(folder / "unsized", std::pair{0.06, 0.04}).surface().height_m(), 0.04);
  try {
    LoadSurface(folder.path());
    FAIL() << "a folder with no material.json was read";
  } catch (const common::Error& e) {
    EXPECT_NE(std::string(e.what()).find("material.json"), std::string::npos) << e.what();
  }
}

// One simulation (about 20 s) serves every check of a truth surface.
TEST(TruthSurface, IsTheAnalyticTruthTheSimulatorRendered) {
  const fs::path truth_folder = SimulatedTruths::TruthFolder("model");
  const LoadedSurface loaded = LoadSurface(truth_folder);
  const simulate::Truth truth = simulate::ReadTruth(truth_folder);
  const Surface& surface = loaded.surface();
  EXPECT_EQ(surface.texels_x(), truth.width());
  EXPECT_DOUBLE_EQ(surface.width_m(), truth.rig().sample.width);
  EXPECT_EQ(surface.description(), "analytic truth");
  BsdfScratch scratch;
  for (const auto& [x, y] : {std::pair{0, 0}, std::pair{truth.width() / 2, truth.height() - 1}}) {
    const model::Bsdf& bsdf = surface.At(x, y, scratch);
    for (const Vec3& wo : {Direction(0, 0), Direction(40, 70)}) {
      for (const Vec3& wi : {model::FlipZ(Direction(10, 30)), model::FlipZ(Direction(45, 200))}) {
        const model::Rgb want = truth.Evaluate(x, y, wi, wo), got = bsdf.Eval(wi, wo);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], want[c], 1e-12 * (1 + want[c]));
      }
      const model::testing::BsdfSamplerCheck c = model::testing::CheckBsdf(bsdf, wo, 100000, 5);
      EXPECT_TRUE(c.Passes()) << "chi2 " << c.chi2 << " over " << c.bins;
    }
  }
  EXPECT_THROW(LoadSurface(truth_folder, std::pair{0.1, 0.1}), common::Error);
}

}  // namespace
}  // namespace svbtdf::render
