// Tests of the renderer-facing BSDFs (model/bsdf.h), in the style of Mitsuba's and pbrt's BSDF
// tests: a chi-square test of Sample against Pdf (with the mass of failed draws as its own bin),
// Sample's pdf and weight against Pdf and Eval, energy, reciprocity, and agreement with the
// material evaluator that fitting and `compare` use.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "svbtdf/common/error.h"
#include "svbtdf/model/bsdf.h"
#include "svbtdf/model/ellipsoid_ndf.h"
#include "svbtdf/model/ggx.h"
#include "svbtdf/model/hemicube.h"
#include "svbtdf/model/slab_transmission.h"
#include "svbtdf/model/tabulated_ndf.h"
#include "sampling_check.h"

namespace svbtdf::model {
namespace {

// The energy a viewer along wo receives per unit irradiance, by a fine quadrature of Eval |cos|
// over wi's side (independent of Sample and Pdf).
double QuadratureEnergy(const Bsdf& bsdf, const Vec3& wo) {
  const Hemicube grid(64);
  const double side = wo.z() > 0 ? -1.0 : 1.0;
  double energy = 0;
  for (int c = 0; c < grid.num_cells(); ++c) {
    const Vec3 d = grid.CellCenter(c);
    energy += Luminance(bsdf.Eval(Vec3(d.x(), d.y(), side * d.z()), wo)) * d.z() * grid.CellSolidAngle(c);
  }
  return energy;
}

Vec3 Direction(double theta_deg, double phi_deg) { return SphericalDirection(theta_deg * kPi / 180, phi_deg * kPi / 180); }

DualMicrofacetParams Params(double alpha, double shadowing_roughness, const Rgb& k_s, const Rgb& rho_d) {
  DualMicrofacetParams p;
  p.eta = 1.5;
  p.alpha = alpha;
  p.shadowing = SmithShadowing::Ggx(shadowing_roughness);
  p.k_s = k_s;
  p.rho_d = rho_d;
  return p;
}

struct NamedNdf {
  std::string name;
  std::shared_ptr<const Ndf> ndf;
};

std::vector<NamedNdf> TestNdfs() {
  const Hemicube grid(32);
  return {{"ggx 0.35", std::make_shared<GgxNdf>(0.35)},
          {"tabulated ggx 0.5 x 0.3", std::make_shared<TabulatedNdf>(grid, GgxNdf(0.5, 0.3))},
          {"ellipsoid 0.4 x 0.25 turned", std::make_shared<EllipsoidNdf>(0.4, 0.25, 0.0, 0.0, 0.6)}};
}

TEST(DualMicrofacetBsdf, SampleFollowsPdfForSeveralNdfsViewsAndBlends) {
  for (const NamedNdf& n : TestNdfs()) {
    for (double alpha : {0.0, 0.5, 0.85}) {
      const DualMicrofacetBsdf bsdf(*n.ndf, Params(alpha, 0.35, {0.9, 0.8, 0.7}, {0.02, 0.03, 0.04}));
      for (const Vec3& wo : {Direction(0, 0), Direction(35, 60), Direction(65, 200), FlipZ(Direction(40, 10))}) {
        const testing::BsdfSamplerCheck c = testing::CheckBsdf(bsdf, wo, 200000, 7);
        const std::string where = n.name + " alpha " + std::to_string(alpha) + " wo.z " + std::to_string(wo.z());
        EXPECT_TRUE(c.Passes()) << where << ": chi2 " << c.chi2 << " over " << c.bins << " bins";
        EXPECT_LE(c.pdf_integral, 1.0 + 5e-3) << where;
        EXPECT_LT(c.max_pdf_mismatch, 1e-9) << where;
        EXPECT_LT(c.max_weight_mismatch, 1e-9) << where;
      }
    }
  }
}

TEST(DualMicrofacetBsdf, EvalIsTheMaterialEvaluatorSeenFromAboveAndZeroOnTheSameSide) {
  const GgxNdf ndf(0.3, 0.2);
  const DualMicrofacetParams p = Params(0.6, 0.3, {0.7, 0.8, 0.9}, {0.01, 0.02, 0.03});
  const DualMicrofacetBsdf bsdf(ndf, p);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0, 1);
  for (int k = 0; k < 500; ++k) {
    const Vec3 o = Direction(80 * u(rng), 360 * u(rng));
    const Vec3 i = FlipZ(Direction(80 * u(rng), 360 * u(rng)));
    const Rgb want = EvaluateMaterial(ndf, p, i, o), got = bsdf.Eval(i, o);
    for (int c = 0; c < 3; ++c) EXPECT_DOUBLE_EQ(got[c], want[c]);
    const Rgb same_side = bsdf.Eval(FlipZ(i), o);
    EXPECT_EQ(same_side[0] + same_side[1] + same_side[2], 0.0);
    EXPECT_EQ(bsdf.Pdf(FlipZ(i), o), 0.0);
  }
}

// Swapping light and viewer turns rough entry into rough exit; with alpha becoming 1 - alpha
// below (bsdf.h), the texel is reciprocal: f(wi, wo) = f(wo, wi) between two air half-spaces.
TEST(DualMicrofacetBsdf, IsReciprocal) {
  for (const NamedNdf& n : TestNdfs()) {
    const DualMicrofacetBsdf bsdf(*n.ndf, Params(0.3, 0.4, {1, 1, 1}, {0.05, 0.05, 0.05}));
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(0, 1);
    double checked = 0;
    for (int k = 0; k < 400; ++k) {
      const Vec3 wo = Direction(85 * u(rng), 360 * u(rng));
      const Vec3 wi = FlipZ(Direction(85 * u(rng), 360 * u(rng)));
      const double forward = Luminance(bsdf.Eval(wi, wo)), backward = Luminance(bsdf.Eval(wo, wi));
      EXPECT_NEAR(forward, backward, 1e-9 * (1 + forward)) << n.name << " at pair " << k;
      if (forward > 0.06) ++checked;
    }
    EXPECT_GT(checked, 20) << n.name << ": the specular part must be exercised, not only rho_d";
  }
}

// With Fresnel and a shadowing roughness at least the NDF's (docs/model.md, "Energy"), a texel
// with k_s = 1 transmits at most what it receives; Sample's estimate agrees with quadrature.
TEST(DualMicrofacetBsdf, EnergyIsAtMostOneAndSampleEstimatesIt) {
  for (const NamedNdf& n : TestNdfs()) {
    for (double alpha : {0.0, 0.5, 1.0}) {
      const DualMicrofacetBsdf bsdf(*n.ndf, Params(alpha, 0.5, {1, 1, 1}, {0, 0, 0}));
      for (const Vec3& wo : {Direction(0, 0), Direction(50, 30), FlipZ(Direction(70, 120))}) {
        const testing::BsdfSamplerCheck c = testing::CheckBsdf(bsdf, wo, 100000, 5);
        const double quadrature = QuadratureEnergy(bsdf, wo);
        const std::string where = n.name + " alpha " + std::to_string(alpha) + " wo.z " + std::to_string(wo.z());
        EXPECT_LE(c.mean_weight, 1.0 + 4 * c.weight_standard_error) << where;
        EXPECT_LE(quadrature, 1.0 + 1e-3) << where;
        EXPECT_GT(quadrature, 0.05) << where;  // 70 degrees from below loses most to Fresnel
        EXPECT_NEAR(c.mean_weight, quadrature, 5 * c.weight_standard_error + 0.01 * quadrature) << where;
      }
    }
  }
}

TEST(DualMicrofacetBsdf, DiffuseOnlyTexelIsLambertianTransmission) {
  const GgxNdf ndf(0.3);
  const DualMicrofacetBsdf bsdf(ndf, Params(0.5, 0.3, {0, 0, 0}, {0.2, 0.25, 0.3}));
  EXPECT_DOUBLE_EQ(bsdf.lobe_weights(false).diffuse, 1.0);
  const testing::BsdfSamplerCheck c = testing::CheckBsdf(bsdf, Direction(30, 0), 100000, 9);
  EXPECT_TRUE(c.Passes()) << c.chi2;
  EXPECT_NEAR(c.mean_weight, kPi * 0.25, 1e-9);  // every weight is exactly pi rho_d
  EXPECT_EQ(c.failure_fraction, 0.0);
}

TEST(WalterBsdf, SampleFollowsPdfAndEvalIsTheBaselineShape) {
  const GgxNdf ndf(0.4, 0.2);
  for (double azimuth : {0.0, 0.7}) {
    const WalterBsdf bsdf(ndf, 1.0, 1.5, {0.8, 0.9, 1.0}, {0.01, 0.01, 0.01}, azimuth);
    for (const Vec3& wo : {Direction(0, 0), Direction(45, 80), FlipZ(Direction(60, 250))}) {
      const testing::BsdfSamplerCheck c = testing::CheckBsdf(bsdf, wo, 200000, 13);
      const std::string where = "azimuth " + std::to_string(azimuth) + " wo.z " + std::to_string(wo.z());
      EXPECT_TRUE(c.Passes()) << where << ": chi2 " << c.chi2 << " over " << c.bins << " bins";
      EXPECT_LT(c.max_pdf_mismatch, 1e-9) << where;
      EXPECT_LT(c.max_weight_mismatch, 1e-9) << where;
    }
    // Eval turns the directions by -azimuth before Walter's BTDF, as the baseline fit does.
    const Vec3 o = Direction(30, 40), i = FlipZ(Direction(20, 250));
    const Eigen::AngleAxisd unrotate(-azimuth, Vec3::UnitZ());
    const double shape = WalterBtdf(ndf, unrotate * i, unrotate * o, 1.0, 1.5);
    EXPECT_NEAR(bsdf.Eval(i, o)[1], 0.9 * shape + 0.01, 1e-12);
  }
}

TEST(SlabBsdf, SampleFollowsPdfAndEvalIsTheTwoInterfaceTransmissionAndItsHalo) {
  const GgxNdf entry(0.3), exit(0.12, 0.2);
  const double w = kLongerPathsWidening;
  const GgxNdf longer_entry(0.3 * w), longer_exit(0.12 * w, 0.2 * w);
  const Rgb k_s = {0.9, 0.8, 0.7}, rho_d = {0.02, 0.03, 0.04};
  const SlabBsdf bsdf(entry, exit, 1.45, k_s, rho_d, SlabInternalLight{1.5, 0.8, &longer_entry, &longer_exit});
  // Each Eval is two integrals (about 50 us): fewer draws than the closed-form BSDFs get.
  for (const Vec3& wo : {Direction(70, 200), FlipZ(Direction(35, 10))}) {
    const testing::BsdfSamplerCheck c = testing::CheckBsdf(bsdf, wo, 50000, 19);
    const std::string where = "wo.z " + std::to_string(wo.z());
    EXPECT_TRUE(c.Passes()) << where << ": chi2 " << c.chi2 << " over " << c.bins << " bins";
    EXPECT_LE(c.pdf_integral, 1.0 + 5e-3) << where;
    EXPECT_LT(c.max_pdf_mismatch, 1e-9) << where;
    EXPECT_LT(c.max_weight_mismatch, 1e-9) << where;
  }
  // Seen from above it is k_s (rho_TT + 1.5 IR + 0.8 IR') + rho_d, IR' the longer paths'; from
  // below, the slab turned over.
  const SlabTransmission above(entry, exit, 1.45), below(exit, entry, 1.45);
  const SlabInternalReflection above_ir(entry, exit, 1.45), below_ir(exit, entry, 1.45);
  const SlabInternalReflection above_longer(longer_entry, longer_exit, 1.45), below_longer(longer_exit, longer_entry, 1.45);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0, 1);
  for (int k = 0; k < 50; ++k) {
    const Vec3 o = Direction(80 * u(rng), 360 * u(rng)), i = FlipZ(Direction(60 * u(rng), 360 * u(rng)));
    const Rgb got = bsdf.Eval(i, o), turned = bsdf.Eval(FlipZ(i), FlipZ(o));
    for (int c = 0; c < 3; ++c) {
      EXPECT_DOUBLE_EQ(got[c], k_s[c] * (above.Rho(i, o) + 1.5 * above_ir.Rho(i, o) + 0.8 * above_longer.Rho(i, o)) + rho_d[c]);
      EXPECT_DOUBLE_EQ(turned[c],
                       k_s[c] * (below.Rho(i, o) + 1.5 * below_ir.Rho(i, o) + 0.8 * below_longer.Rho(i, o)) + rho_d[c]);
    }
  }
}

// Light and viewer swapped is the slab seen from the other side: reciprocal to the accuracy of
// the integral's quadrature (the two sides sample different directions). With k_s = 1 it
// transmits at most what it receives, and Sample's weights estimate what quadrature finds.
// A weight of the longer paths without their NDFs is refused, as is a negative weight.
TEST(SlabBsdf, RefusesLongerPathsWithoutTheirNdfsAndNegativeWeights) {
  const GgxNdf entry(0.3), exit(0.12);
  EXPECT_THROW(SlabBsdf(entry, exit, 1.5, {1, 1, 1}, {0, 0, 0}, SlabInternalLight{0.0, 0.5}), common::Error);
  EXPECT_THROW(SlabBsdf(entry, exit, 1.5, {1, 1, 1}, {0, 0, 0}, SlabInternalLight{-1.0}), common::Error);
  EXPECT_NO_THROW(SlabBsdf(entry, exit, 1.5, {1, 1, 1}, {0, 0, 0}, SlabInternalLight{0.5, 0.5, &entry, &exit}));
}

TEST(SlabBsdf, IsReciprocalAndSampleEstimatesItsEnergy) {
  const GgxNdf entry(0.25), exit(0.1);
  const SlabBsdf bsdf(entry, exit, 1.5, {1, 1, 1}, {0, 0, 0});
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  int checked = 0;
  for (int k = 0; k < 300; ++k) {
    const Vec3 wo = Direction(60 * u(rng), 360 * u(rng));
    const Vec3 wi = FlipZ(Direction(60 * u(rng), 360 * u(rng)));
    const double forward = Luminance(bsdf.Eval(wi, wo)), backward = Luminance(bsdf.Eval(wo, wi));
    if (forward < 0.05) continue;  // far tails, where a relative error means little
    EXPECT_NEAR(backward / forward, 1.0, 0.02) << "pair " << k;
    ++checked;
  }
  EXPECT_GT(checked, 20);
  for (const Vec3& wo : {Direction(50, 30), FlipZ(Direction(60, 120))}) {
    const testing::BsdfSamplerCheck c = testing::CheckBsdf(bsdf, wo, 30000, 23);
    const double quadrature = QuadratureEnergy(bsdf, wo);
    const std::string where = "wo.z " + std::to_string(wo.z());
    EXPECT_LE(quadrature, 1.0) << where;
    EXPECT_GT(quadrature, 0.3) << where;  // two interfaces' Fresnel at 60 degrees take much
    EXPECT_NEAR(c.mean_weight, quadrature, 5 * c.weight_standard_error + 0.01 * quadrature) << where;
  }
}

TEST(EvaluatedBsdf, SamplesTheCosineAndEvaluatesWhatItIsGiven) {
  const GgxNdf ndf(0.3);
  const DualMicrofacetParams p = Params(0.5, 0.3, {1, 1, 1}, {0.05, 0.05, 0.05});
  const EvaluatedBsdf bsdf([&](const Vec3& i, const Vec3& o) { return EvaluateMaterial(ndf, p, i, o); });
  const DualMicrofacetBsdf reference(ndf, p);
  for (const Vec3& wo : {Direction(10, 0), Direction(55, 300)}) {
    const testing::BsdfSamplerCheck c = testing::CheckBsdf(bsdf, wo, 200000, 17);
    EXPECT_TRUE(c.Passes()) << c.chi2;
    EXPECT_NEAR(c.pdf_integral, 1.0, 5e-3);
    EXPECT_NEAR(c.mean_weight, QuadratureEnergy(reference, wo), 5 * c.weight_standard_error);
  }
  const Vec3 wo = Direction(30, 10), wi = FlipZ(Direction(20, 190));
  EXPECT_DOUBLE_EQ(bsdf.Eval(wi, wo)[0], reference.Eval(wi, wo)[0]);
}

}  // namespace
}  // namespace svbtdf::model
