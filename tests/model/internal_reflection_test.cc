// Tests of the internal-reflection term (model/internal_reflection.h): the smooth-slab limit of its
// energy (the Fresnel series' second term), convergence of its quadrature, the reciprocity that
// defines the rough-exit configuration, and the material evaluator and BSDF that carry it. Its
// agreement with the Monte Carlo slab (a cap of four interface hits) is tested in
// tests/simulate/slab_tracer_test.cc.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

#include "sampling_check.h"
#include "light_hemisphere.h"
#include "svbtdf/common/error.h"
#include "svbtdf/model/beckmann.h"
#include "svbtdf/model/bsdf.h"
#include "svbtdf/model/ellipsoid_ndf.h"
#include "svbtdf/model/fresnel.h"
#include "svbtdf/model/ggx.h"
#include "svbtdf/model/hemicube.h"
#include "svbtdf/model/internal_reflection.h"

namespace svbtdf::model {
namespace {

Vec3 Direction(double theta_deg, double phi_deg) { return SphericalDirection(theta_deg * kPi / 180, phi_deg * kPi / 180); }

using testing::EnergyOverLights;

// A nearly smooth slab sends (1 - F)^2 F^2 of the light through one internal round trip, F the
// air-side Fresnel reflectance of the view angle (both internal reflections see the in-slab
// angle, whose F is the same). Only nearly: the tail of the rough reflection that reaches the
// critical angle is totally reflected at the flat side (F = 1 instead of 0.04), which even at
// roughness 0.08 and 50 degrees adds 60% to the rough entry's term; hence a very smooth NDF
// and moderate angles, and a rougher one must send more.
TEST(InternalReflection, NearlySmoothSlabSendsTheSecondTermOfTheFresnelSeries) {
  const double eta = 1.5;
  const BeckmannNdf ndf(0.03), rough_ndf(0.2);
  const InternalReflection fine(eta, {64, 32});
  for (double theta : {0.0, 20.0}) {
    const Vec3 o = Direction(theta, 20.0);
    const double f = FresnelDielectric(o.z(), eta);
    const double expected = Square((1.0 - f) * f);
    for (bool rough_exit : {false, true}) {
      const double energy = EnergyOverLights(
          [&](const Vec3& i) { return rough_exit ? fine.RoughExit(ndf, i, o) : fine.RoughEntry(ndf, i, o); }, 40);
      EXPECT_NEAR(energy / expected, 1.0, 0.03) << "theta " << theta << (rough_exit ? " rough exit" : " rough entry");
    }
    const double rough_entry = EnergyOverLights([&](const Vec3& i) { return fine.RoughEntry(rough_ndf, i, o); }, 24);
    EXPECT_GT(rough_entry, 1.2 * expected) << "theta " << theta;
  }
}

// The default quadrature (what the model and validate-model use) against a much finer one.
TEST(InternalReflection, DefaultQuadratureHasConverged) {
  const double eta = 1.5;
  const InternalReflection standard(eta), fine(eta, {96, 64});
  for (double roughness : {0.2, 0.5}) {
    const BeckmannNdf ndf(roughness);
    for (double theta : {0.0, 60.0}) {
      const Vec3 o = Direction(theta, 0.0);
      const double reference = EnergyOverLights([&](const Vec3& i) { return fine.RoughEntry(ndf, i, o); }, 16);
      const double energy = EnergyOverLights([&](const Vec3& i) { return standard.RoughEntry(ndf, i, o); }, 16);
      EXPECT_GT(reference, 1e-3);
      EXPECT_NEAR(energy / reference, 1.0, 0.02) << "roughness " << roughness << " theta " << theta;
    }
  }
}

// The slab is reciprocal: swapping light and camera and turning the slab over maps the rough entry
// onto the rough exit. Checked pointwise with a skewed NDF against a rough entry whose NDF is
// explicitly turned by half a turn about z.
TEST(InternalReflection, RoughExitIsTheRoughEntryTurnedOver) {
  const EllipsoidNdf skewed(0.35, 0.2, 0.15, -0.1, 0.5);
  class HalfTurned final : public Ndf {
   public:
    explicit HalfTurned(const Ndf& ndf) : ndf_(ndf) {}
    std::string name() const override { return "half-turned"; }
    double D(const Vec3& h) const override { return ndf_.D(Turn(h)); }
    double G1(const Vec3& v, const Vec3& h) const override { return ndf_.G1(Turn(v), Turn(h)); }
    NormalSample SampleVisibleNormal(const Vec3&, const Vec2&) const override { return {}; }
    double VisibleNormalPdf(const Vec3&, const Vec3&) const override { return 0; }
    std::unique_ptr<Ndf> Clone() const override { return std::make_unique<HalfTurned>(ndf_); }

   private:
    static Vec3 Turn(const Vec3& v) { return {-v.x(), -v.y(), v.z()}; }
    const Ndf& ndf_;
  };
  const HalfTurned turned(skewed);
  const InternalReflection ir(1.5);
  int nonzero = 0;
  for (const Vec3& o : {Direction(10, 30), Direction(45, 100), Direction(65, 250)}) {
    for (const Vec3& i : {FlipZ(Direction(5, 200)), FlipZ(Direction(40, 310)), FlipZ(Direction(70, 20))}) {
      const double exit = ir.RoughExit(skewed, i, o);
      EXPECT_NEAR(exit, ir.RoughEntry(turned, FlipZ(o), FlipZ(i)), 1e-12 * std::max(1.0, exit));
      // The half turn matters for a skewed NDF: without it the values differ.
      if (exit > 1e-4) {
        ++nonzero;
        EXPECT_GT(std::abs(exit - ir.RoughEntry(skewed, FlipZ(o), FlipZ(i))), 1e-3 * exit);
      }
    }
  }
  EXPECT_GT(nonzero, 3);
}

TEST(InternalReflection, RejectsBadParameters) {
  EXPECT_THROW(InternalReflection(1.0), common::Error);
  EXPECT_THROW(InternalReflection(1.5, {1, 8}), common::Error);
}

// With the option the material evaluator adds k_s IR (blended like the direct terms), and the
// BSDF's sampler, which gives the cosine a larger share to cover the halo, still follows its pdf.
TEST(InternalReflection, MaterialAndBsdfCarryTheTerm) {
  const GgxNdf ndf(0.3);
  DualMicrofacetParams params;
  params.eta = 1.5;
  params.alpha = 0.6;
  params.shadowing = SmithShadowing::Ggx(0.3);
  params.k_s = {0.9, 0.8, 0.7};
  params.rho_d = {0.01, 0.01, 0.01};
  DualMicrofacetParams with = params;
  with.internal_reflection = true;
  const Vec3 o = Direction(50, 10), i = FlipZ(Direction(20, 150));
  const double ir = InternalReflection(1.5).Blend(ndf, 0.6, i, o);
  EXPECT_GT(ir, 0.0);
  EXPECT_NEAR(EvaluateMaterial(ndf, with, i, o)[1] - EvaluateMaterial(ndf, params, i, o)[1], 0.8 * ir, 1e-12);
  const DualMicrofacetBsdf bsdf(ndf, with);
  EXPECT_NEAR(bsdf.Eval(i, o)[2], EvaluateMaterial(ndf, with, i, o)[2], 1e-12);
  EXPECT_GE(bsdf.lobe_weights(false).diffuse, 0.2);
  // Every sample's weight calls Eval, whose term is a quadrature: fewer samples keep this fast.
  for (const Vec3& wo : {Direction(60, 30), FlipZ(Direction(35, 80))}) {
    const testing::BsdfSamplerCheck c = testing::CheckBsdf(bsdf, wo, 15000, 9);
    EXPECT_TRUE(c.Passes()) << "wo.z " << wo.z() << ": chi2 " << c.chi2 << " over " << c.bins << " bins";
    EXPECT_LT(c.max_pdf_mismatch, 1e-9);
    EXPECT_LT(c.max_weight_mismatch, 1e-9);
  }
}

}  // namespace
}  // namespace svbtdf::model
