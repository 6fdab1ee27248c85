// Tests of the two-rough-interface transmission (model/slab_transmission.h): its one-rough-side
// limits (the dual-microfacet configurations, which are exact there), the smooth slab's energy,
// reciprocity, and its quadrature's convergence. Its agreement with the Monte Carlo slab (a cap
// of two interface hits, both sides rough) is tested in tests/simulate/slab_tracer_test.cc.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "light_hemisphere.h"
#include "svbtdf/common/error.h"
#include "svbtdf/model/beckmann.h"
#include "svbtdf/model/dual_microfacet.h"
#include "svbtdf/model/fresnel.h"
#include "svbtdf/model/ggx.h"
#include "svbtdf/model/hemicube.h"
#include "svbtdf/model/slab_transmission.h"

namespace svbtdf::model {
namespace {

Vec3 Direction(double theta_deg, double phi_deg) { return SphericalDirection(theta_deg * kPi / 180, phi_deg * kPi / 180); }

Vec3 ScaledSlabDirection(const Vec3& v, double eta) {
  return {v.x(), v.y(), std::sqrt(eta * eta - v.x() * v.x() - v.y() * v.y())};
}

// The exact one-rough-side configurations with the NDF's own shadowing (docs/model.md): a rough
// entry and a flat exit, rho_T = (1 - F(o.z)) f_W(i -> t) / eta^2 with t the in-slab direction
// that leaves along o; a flat entry and a rough exit, rho_B = (1 - F(|i.z|)) f_W(-t_i -> o).
double RoughEntryOnly(const Ndf& ndf, double eta, const Vec3& i, const Vec3& o) {
  const Vec3 t = ScaledSlabDirection(o, eta) / eta;
  return (1.0 - FresnelDielectric(o.z(), eta)) * WalterBtdf(ndf, i, t, 1.0, eta) / (eta * eta);
}

double RoughExitOnly(const Ndf& ndf, double eta, const Vec3& i, const Vec3& o) {
  const Vec3 t = ScaledSlabDirection(FlipZ(-i), eta) / eta;  // the light's in-slab direction, travelling up
  return (1.0 - FresnelDielectric(-i.z(), eta)) * WalterBtdf(ndf, -t, o, eta, 1.0);
}

// Relative L2 distance of two functions of the light direction over a hemicube's cell centres,
// weighted by solid angle.
template <typename F, typename G>
double RelativeL2(const F& f, const G& g, int resolution = 24) {
  const Hemicube grid(resolution);
  double difference = 0, norm = 0;
  for (int c = 0; c < grid.num_cells(); ++c) {
    const Vec3 i = FlipZ(grid.CellCenter(c));
    const double a = f(i), b = g(i);
    difference += grid.CellSolidAngle(c) * Square(a - b);
    norm += grid.CellSolidAngle(c) * Square(b);
  }
  return std::sqrt(difference / norm);
}

using testing::EnergyOverLights;

// With one interface nearly flat (GGX 0.0005, a blur of a few hundredths of a degree), the integral is the
// other side's exact configuration: the exit's sampling resolves a narrow exit, the entry's a
// narrow entry, whichever side is rough.
TEST(SlabTransmission, OneNearlyFlatSideGivesTheOtherSidesConfiguration) {
  const double eta = 1.5;
  const GgxNdf rough(0.3), skewed_rough(0.15, 0.35), flat(0.0005);
  for (const Ndf* ndf : {static_cast<const Ndf*>(&rough), static_cast<const Ndf*>(&skewed_rough)}) {
    for (double theta : {0.0, 30.0, 55.0}) {
      const Vec3 o = Direction(theta, 25.0);
      const SlabTransmission entry_rough(*ndf, flat, eta), exit_rough(flat, *ndf, eta);
      const SlabTransmission::ForViewer entry_view = entry_rough.Viewer(o), exit_view = exit_rough.Viewer(o);
      const double entry_error = RelativeL2([&](const Vec3& i) { return entry_view.Rho(i); },
                                            [&](const Vec3& i) { return RoughEntryOnly(*ndf, eta, i, o); });
      const double exit_error = RelativeL2([&](const Vec3& i) { return exit_view.Rho(i); },
                                           [&](const Vec3& i) { return RoughExitOnly(*ndf, eta, i, o); });
      EXPECT_LT(entry_error, 0.01) << "rough entry, theta " << theta;
      EXPECT_LT(exit_error, 0.01) << "rough exit, theta " << theta;
    }
  }
}

// A nearly smooth slab transmits (1 - F(o.z))^2 of the light (both interfaces see the same
// angles, through the in-slab direction), and absorption takes exp(-tau / t.z) of that.
TEST(SlabTransmission, NearlySmoothSlabTransmitsTheFresnelProductAndItsAbsorption) {
  const double eta = 1.5;
  const GgxNdf entry(0.03), exit(0.02);
  for (double tau : {0.0, 0.3}) {
    for (double theta : {0.0, 40.0}) {
      const Vec3 o = Direction(theta, 10.0);
      const SlabTransmission slab(entry, exit, eta, tau);
      const SlabTransmission::ForViewer view = slab.Viewer(o);
      const double t_z = ScaledSlabDirection(o, eta).z() / eta;
      const double expected = Square(1.0 - FresnelDielectric(o.z(), eta)) * std::exp(-tau / t_z);
      EXPECT_NEAR(EnergyOverLights([&](const Vec3& i) { return view.Rho(i); }, 96) / expected, 1.0, 0.02)
          << "tau " << tau << ", theta " << theta;
    }
  }
}

// The slab turned over (z -> -z) with light and camera swapped is the slab whose entry is the old
// exit: rho(i, o) = rho'(flip o, flip i). The two sides' quadratures sample different directions,
// so they agree to the quadrature's accuracy, not exactly.
TEST(SlabTransmission, IsReciprocal) {
  const double eta = 1.45;
  const GgxNdf entry(0.25), exit(0.12);
  const SlabTransmission slab(entry, exit, eta, 0.05), turned(exit, entry, eta, 0.05, {24});
  const SlabTransmission fine(entry, exit, eta, 0.05, {24});
  for (double theta : {10.0, 45.0}) {
    const Vec3 o = Direction(theta, 70.0);
    const SlabTransmission::ForViewer view = fine.Viewer(o);
    double worst = 0;
    for (double light_theta : {5.0, 20.0, 35.0, 50.0}) {
      for (double phi : {0.0, 90.0, 250.0}) {
        const Vec3 i = FlipZ(Direction(light_theta, phi));
        const double rho = view.Rho(i);
        if (rho < 1e-3 * view.Rho(FlipZ(-o))) continue;  // far tails: relative error means little
        worst = std::max(worst, std::abs(turned.Rho(FlipZ(o), FlipZ(i)) / rho - 1.0));
      }
    }
    EXPECT_LT(worst, 0.01) << "theta " << theta;
  }
}

// The default quadrature (8 x 8 per side) against a 32 x 32 one, for lobes of every width the
// fit can meet, both sides rough.
TEST(SlabTransmission, TheDefaultQuadratureIsWithinTwoPercentOfAFineOne) {
  const double eta = 1.5;
  struct Case {
    double entry, exit, theta;
  };
  for (const Case& c : {Case{0.3, 0.12, 45.0}, Case{0.12, 0.3, 45.0}, Case{0.05, 0.05, 30.0},
                        Case{0.6, 0.5, 60.0}, Case{0.02, 0.4, 45.0}}) {
    const GgxNdf entry(c.entry), exit(c.exit);
    const SlabTransmission coarse(entry, exit, eta), fine(entry, exit, eta, 0.0, {32});
    const Vec3 o = Direction(c.theta, 30.0);
    const SlabTransmission::ForViewer coarse_view = coarse.Viewer(o), fine_view = fine.Viewer(o);
    const double error = RelativeL2([&](const Vec3& i) { return coarse_view.Rho(i); },
                                    [&](const Vec3& i) { return fine_view.Rho(i); }, 24);
    std::printf("entry %.2f exit %.2f theta %.0f: relative L2 %.4f\n", c.entry, c.exit, c.theta, error);
    EXPECT_LT(error, 0.02) << "entry " << c.entry << ", exit " << c.exit << ", theta " << c.theta;
  }
}

TEST(SlabTransmission, RefusesABadSlab) {
  const GgxNdf ndf(0.2);
  EXPECT_THROW(SlabTransmission(ndf, ndf, 1.0), common::Error);
  EXPECT_THROW(SlabTransmission(ndf, ndf, 1.5, -0.1), common::Error);
  EXPECT_THROW(SlabTransmission(ndf, ndf, 1.5, 0.0, {1}), common::Error);
  const SlabTransmission slab(ndf, ndf, 1.5);
  EXPECT_EQ(slab.Rho(Direction(20, 0), Direction(10, 0)), 0.0);  // light on the camera's side
}

}  // namespace
}  // namespace svbtdf::model
