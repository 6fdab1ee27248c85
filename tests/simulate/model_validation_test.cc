// The claims of the dual-microfacet paper (its Figs. 3 and 5) that `svbtdf validate-model`
// reproduces, checked against the Monte Carlo slab (issue 3, docs/validation.md). The slab and the
// models share a Beckmann NDF, roughness 0.3, eta 1.5, as in the paper's Gaussian-NDF experiment.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "svbtdf/simulate/model_validation.h"
#include "test_ndfs.h"

namespace svbtdf::simulate {
namespace {

std::vector<ValidationCase> Validate(RoughSides sides) {
  ValidationOptions options;
  options.make_ndf = [](double roughness) { return PaperNdf(roughness); };
  options.roughness = 0.3;
  options.configurations = {sides};
  options.fit_blend_roughness = false;
  options.slice.paths = 1000000;
  options.slice.seed = 5;
  return ValidateModel(options, model::Hemicube(32));
}

void Print(const ValidationCase& c) {
  std::printf("%s %2.0f: rho_T %.3f rho_B %.3f blend %.3f (alpha %.3f) single %.3f fitted %.3f slab lobe %.3f "
              "blend + internal %.3f two interfaces %.3f, + internal %.3f (weight %.2f), + longer %.3f (weights %.2f, "
              "%.2f); noise %.4f\n",
              ToString(c.rough_sides), c.incidence_deg, c.errors.rho_T, c.errors.rho_B,
              c.errors.blend, c.best_alpha, c.errors.single_same_ndf, c.errors.single_fitted, c.errors.slab_lobe,
              c.errors.blend_internal, c.errors.two_interfaces, c.errors.two_interfaces_internal,
              c.two_interfaces_internal_weight, c.errors.two_interfaces_internal_longer, c.longer_internal_weight,
              c.longer_longer_weight, c.mc_noise);
}

// Issue 21: the internal-reflection term never makes a case worse, and with one rough side it
// removes a real share of the error at 60 degrees (where light reflected inside the slab
// matters). It does not reach MC noise there: paths of six and more hits remain (docs/validation.md).
void ExpectInternalReflectionHelps(const ValidationCase& c) {
  EXPECT_LE(c.errors.blend_internal, c.errors.blend + 2e-3) << "incidence " << c.incidence_deg;
  if (c.rough_sides != RoughSides::kBoth && c.incidence_deg >= 60) {
    EXPECT_LT(c.errors.blend_internal, 0.8 * c.errors.blend) << "incidence " << c.incidence_deg;
  }
  // The slab model's form: its internal reflection at a fitted weight never does worse than none,
  // nor the longer paths' shape beside it.
  EXPECT_LE(c.errors.two_interfaces_internal, c.errors.two_interfaces + 1e-12) << "incidence " << c.incidence_deg;
  EXPECT_LE(c.errors.two_interfaces_internal_longer, c.errors.two_interfaces_internal + 1e-12)
      << "incidence " << c.incidence_deg;
  // With one rough side, at 60 degrees, the two shapes leave the model's own error (the MC noise
  // taken out in quadrature, so that the bound does not depend on the paths traced) below 0.025:
  // within 3x the noise of docs/validation.md's 4M-path run (0.0092-0.0096). Measured there 0.019
  // (entry) and 0.014 (exit); one shape alone leaves 0.036 and 0.022.
  if (c.rough_sides != RoughSides::kBoth && c.incidence_deg >= 60) {
    const double own = std::sqrt(std::max(0.0, model::Square(c.errors.two_interfaces_internal_longer) - model::Square(c.mc_noise)));
    EXPECT_LT(own, 0.025) << "incidence " << c.incidence_deg << ", error " << c.errors.two_interfaces_internal_longer
                          << ", noise " << c.mc_noise;
  }
}

// With one side flat (a roughness of 5e-4) the exact two-interface transmission is that side's
// configuration; measured within 0.001 of its error.
void ExpectTwoInterfacesAreTheConfiguration(const ValidationCase& c, double configuration_error) {
  EXPECT_NEAR(c.errors.two_interfaces, configuration_error, 0.005) << "incidence " << c.incidence_deg;
  // With the internal reflection at its fitted weight, better than at weight 1 (the one-rough-side
  // T R R T term is the same): the weight stands for the longer paths too.
  EXPECT_LT(c.errors.two_interfaces_internal, c.errors.blend_internal + 2e-3) << "incidence " << c.incidence_deg;
}

// Fig. 3(a): only the light-facing side rough -> rho_T is the right configuration.
TEST(ValidateModel, RhoTBeatsRhoBWhenOnlyTheEntryIsRough) {
  for (const ValidationCase& c : Validate(RoughSides::kEntry)) {
    Print(c);
    EXPECT_LT(c.errors.rho_T, c.errors.rho_B) << "incidence " << c.incidence_deg;
    ExpectInternalReflectionHelps(c);
    ExpectTwoInterfacesAreTheConfiguration(c, c.errors.rho_T);
  }
}

// Fig. 3(b): only the camera-facing side rough -> rho_B.
TEST(ValidateModel, RhoBBeatsRhoTWhenOnlyTheExitIsRough) {
  for (const ValidationCase& c : Validate(RoughSides::kExit)) {
    Print(c);
    EXPECT_LT(c.errors.rho_B, c.errors.rho_T) << "incidence " << c.incidence_deg;
    ExpectInternalReflectionHelps(c);
    ExpectTwoInterfacesAreTheConfiguration(c, c.errors.rho_B);
  }
}

// Fig. 5: equal roughness on both sides -> an intermediate alpha (the paper found 0.56), and the
// blend beats the single-refraction model with the same NDF at 30, 45 and 60 degrees.
TEST(ValidateModel, EqualRoughnessWantsAnIntermediateAlphaAndBeatsTheSingleInterface) {
  const std::vector<ValidationCase> cases = Validate(RoughSides::kBoth);
  ASSERT_EQ(cases.size(), 3u);
  for (const ValidationCase& c : cases) {
    Print(c);
    EXPECT_GE(c.best_alpha, 0.35) << "incidence " << c.incidence_deg;
    EXPECT_LE(c.best_alpha, 0.75) << "incidence " << c.incidence_deg;
    EXPECT_LT(c.errors.blend, c.errors.single_same_ndf) << "incidence " << c.incidence_deg;
    // The best blend can never be worse than either end point it includes.
    EXPECT_LE(c.errors.blend, std::min(c.errors.rho_T, c.errors.rho_B) + 1e-12);
    ExpectInternalReflectionHelps(c);
    // The exact convolution of the two interfaces (model/slab_transmission.h) with the slab's own
    // NDFs, nothing fitted: measured 0.041, 0.076, 0.139 against the blend's 0.526, 0.472, 0.333.
    EXPECT_LT(c.errors.two_interfaces, 0.5 * c.errors.blend) << "incidence " << c.incidence_deg;
    // Seed 000's slab lobe convolves the two interfaces, which the same-NDF blend cannot: it is
    // closer to the MC lobe up to 45 degrees. At 60 degrees its isotropic lobe reaches the horizon
    // and fails (docs/validation.md).
    if (c.incidence_deg <= 45) {
      EXPECT_LT(c.errors.slab_lobe, 0.6 * c.errors.blend) << "incidence " << c.incidence_deg;
    }
  }
}

TEST(MinimiseOnInterval, FindsTheMinimumOfAUnimodalFunction) {
  EXPECT_NEAR(MinimiseOnInterval([](double x) { return model::Square(x - 0.37); }, 0.0, 1.0), 0.37, 1e-4);
  EXPECT_NEAR(MinimiseOnInterval([](double x) { return std::abs(x + 2.0); }, -3.0, 5.0), -2.0, 1e-4);
  // At the end of the interval.
  EXPECT_NEAR(MinimiseOnInterval([](double x) { return x; }, 0.0, 1.0), 0.0, 1e-4);
}

TEST(CellAverager, AveragesReproduceSolidAngleIntegrals) {
  const model::Hemicube grid(16);
  const CellAverager averager(grid, 4);
  // Integral of |i.z| over the lower hemisphere is pi; of 1 is 2 pi.
  const std::vector<double> cosine = averager.Average([](const model::Vec3& i) { return std::abs(i.z()); });
  const std::vector<double> one = averager.Average([](const model::Vec3&) { return 1.0; });
  double cosine_integral = 0.0, solid_angle = 0.0;
  for (int c = 0; c < grid.num_cells(); ++c) {
    cosine_integral += cosine[c] * grid.CellSolidAngle(c);
    solid_angle += one[c] * grid.CellSolidAngle(c);
    EXPECT_NEAR(one[c], 1.0, 1e-12);
  }
  EXPECT_NEAR(solid_angle, model::kTwoPi, 1e-9);
  // The sub-cell midpoint rule is second order: sub-cells 1/64 of a face wide leave ~1e-4.
  EXPECT_NEAR(cosine_integral, model::kPi, 5e-4);
}

}  // namespace
}  // namespace svbtdf::simulate
