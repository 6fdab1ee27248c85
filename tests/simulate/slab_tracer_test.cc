// Tests of the Monte Carlo slab tracer against physics it must obey (docs/validation.md):
// per-path energy conservation, the closed-form smooth slab, the one-rough-side limits where the
// dual-microfacet configurations are exact, reciprocity, and determinism.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "svbtdf/common/error.h"
#include "svbtdf/model/fresnel.h"
#include "svbtdf/model/internal_reflection.h"
#include "svbtdf/model/slab_transmission.h"
#include "svbtdf/simulate/model_validation.h"
#include "svbtdf/simulate/slab_tracer.h"
#include "test_ndfs.h"

namespace svbtdf::simulate {
namespace {

model::Vec3 ViewDirection(double theta_deg, double phi_deg = 0.0) {
  return model::SphericalDirection(theta_deg * model::kPi / 180.0, phi_deg * model::kPi / 180.0);
}

model::Vec3 LightDirection(double theta_deg, double phi_deg = 0.0) {
  return model::FlipZ(ViewDirection(theta_deg, phi_deg));
}

TEST(SlabTracer, EveryPathsEnergyIsAccountedFor) {
  Slab slab;
  slab.eta = 1.5;
  slab.entry = SlabInterface::Rough(*SkewedNdf());
  slab.exit = SlabInterface::Rough(*RoughNdf(0.6));
  slab.optical_depth = 0.3;
  const SlabTracer tracer(slab);
  common::Pcg32 rng(7, 0);
  int left = 0, capped = 0, masked = 0;
  for (int p = 0; p < 50000; ++p) {
    const model::Vec3 arrival = p % 2 == 0 ? model::Vec3(-ViewDirection(70.0 * (p % 7) / 6, 13.0 * p))
                                    : model::Vec3(-LightDirection(70.0 * (p % 5) / 4, 29.0 * p));
    const PathRecord path = tracer.TracePath(arrival, rng, /*max_interactions=*/4);
    const EnergyFractions& e = path.energy;
    ASSERT_NEAR(e.Total(), 1.0, 1e-12) << "path " << p;
    ASSERT_GE(e.transmitted, 0.0);
    ASSERT_GE(e.reflected, 0.0);
    ASSERT_GE(e.absorbed, 0.0);
    ASSERT_GE(e.masked, 0.0);
    ASSERT_GE(e.capped, 0.0);
    ASSERT_LE(path.interactions, 4);
    if (path.left_slab) {
      ASSERT_NEAR(path.direction.norm(), 1.0, 1e-12);
      ASSERT_EQ(path.transmitted, (path.direction.z() > 0) == (arrival.z() > 0));
      ++left;
    }
    capped += e.capped > 0;
    masked += e.masked > 0;
  }
  // Every kind of outcome must actually occur, or the test proves nothing.
  EXPECT_GT(left, 1000);
  EXPECT_GT(capped, 10);
  EXPECT_GT(masked, 1000);
}

// A smooth slab: (1-F) enters, and every round trip inside returns F^2 a^2 of it, where a is the
// attenuation of one crossing, so T = (1-F)^2 a / (1 - F^2 a^2), R = F + (1-F)^2 F a^2 / (1 - F^2 a^2).
TEST(SlabTracer, SmoothSlabMatchesTheFresnelSeries) {
  for (double tau : {0.0, 0.2}) {
    for (double theta : {0.0, 40.0, 75.0}) {
      Slab slab;
      slab.eta = 1.5;
      slab.optical_depth = tau;
      const SlabTracer tracer(slab);
      const model::Vec3 o = ViewDirection(theta, 30.0);
      const double f = model::FresnelDielectric(o.z(), slab.eta);
      const double cos_t = std::sqrt(1.0 - (1.0 - o.z() * o.z()) / model::Square(slab.eta));
      const double a = std::exp(-tau / cos_t);
      const double transmitted = model::Square(1.0 - f) * a / (1.0 - model::Square(f * a));
      const double reflected = f + model::Square(1.0 - f) * f * a * a / (1.0 - model::Square(f * a));

      SliceOptions options;
      options.paths = 400000;
      options.seed = 3;
      const BtdfSlice slice = tracer.SliceForView(o, model::Hemicube(8), options);
      const EnergyFractions& e = slice.fractions;
      const EnergyFractions& se = slice.fractions_standard_error;
      EXPECT_NEAR(e.Total(), 1.0, 1e-12);
      EXPECT_NEAR(e.transmitted, transmitted, 4.0 * se.transmitted + 1e-12) << "theta " << theta;
      EXPECT_NEAR(e.reflected, reflected, 4.0 * se.reflected + 1e-12) << "theta " << theta;
      EXPECT_NEAR(e.absorbed, 1.0 - transmitted - reflected, 4.0 * se.absorbed + 1e-12);
      EXPECT_EQ(e.masked, 0.0);
      EXPECT_LT(e.capped, 1e-12);
      // All transmitted light leaves straight through, along i = -o.
      const model::Hemicube grid(8);
      const int straight = grid.CellOf(model::FlipZ(-o));
      EXPECT_NEAR(slice.energy[straight], e.transmitted, 1e-12);
    }
  }
}

// Compares an MC slice with a model's cell averages. Unbiased agreement means the differences are
// MC noise: over well-sampled cells (>= 200 paths) chi^2 / dof must be 1 within 5 of its own
// standard deviations sqrt(2 / dof), and the solid-angle-weighted relative L2 error must be at
// most twice the one that the standard errors alone predict.
void ExpectAgreement(const BtdfSlice& mc, const std::vector<double>& model, const model::Hemicube& grid,
                     const std::string& what) {
  double chi2 = 0.0;
  int dof = 0;
  double noise = 0.0;
  double norm = 0.0;
  std::vector<double> solid_angles(grid.num_cells());
  for (int c = 0; c < grid.num_cells(); ++c) {
    solid_angles[c] = grid.CellSolidAngle(c);
    noise += solid_angles[c] * model::Square(mc.standard_error[c]);
    norm += solid_angles[c] * model::Square(mc.rho[c]);
    if (mc.hits[c] < 200) continue;
    chi2 += model::Square((mc.rho[c] - model[c]) / mc.standard_error[c]);
    ++dof;
  }
  ASSERT_GT(dof, 30) << what;
  const double error = RelativeL2Error(model, mc.rho, solid_angles);
  const double expected = std::sqrt(noise / norm);
  EXPECT_NEAR(chi2 / dof, 1.0, 5.0 * std::sqrt(2.0 / dof)) << what << ": chi2 " << chi2 << " dof " << dof;
  EXPECT_LE(error, 2.0 * expected) << what << ": relative L2 " << error << ", noise alone " << expected;
  std::printf("%s: chi2/dof %.3f (dof %d), relative L2 %.4f (noise alone %.4f)\n", what.c_str(),
              chi2 / dof, dof, error, expected);
}

// One side rough (the skewed NDF), the other flat: the tracer capped at `max_interactions`
// interface hits against the direct configuration that owns such a slab (rho_T for a rough entry,
// rho_B for a rough exit), plus, with a cap of four, the internal-reflection term.
//  - A cap of two keeps inter-reflections out: the direct configuration alone is exact.
//  - A cap of four adds exactly the paths reflected once by each interface inside the slab
//    (T R R T; three hits leave back toward the light), which the term models.
// The term is smooth, so it is averaged on fewer points per cell than the direct lobe.
void ExpectOneRoughSideAgrees(bool rough_exit, int max_interactions) {
  const std::unique_ptr<model::Ndf> ndf = SkewedNdf();
  Slab slab;
  slab.eta = 1.5;
  (rough_exit ? slab.exit : slab.entry) = SlabInterface::Rough(*ndf);
  const SlabTracer tracer(slab);
  const model::Hemicube grid(32);
  const CellAverager direct_averager(grid, 6), halo_averager(grid, 2);
  const model::InternalReflection internal(slab.eta);
  const bool with_internal_reflection = max_interactions >= 4;
  for (double theta : {30.0, 60.0}) {
    const model::Vec3 o = ViewDirection(theta, 20.0);
    SliceOptions options;
    options.paths = 2000000;
    options.max_interactions = max_interactions;
    const BtdfSlice mc = tracer.SliceForView(o, grid, options);
    std::vector<double> model = direct_averager.Average([&](const model::Vec3& i) {
      return rough_exit ? RhoBWithNdfShadowing(*ndf, slab.eta, i, o) : RhoTWithNdfShadowing(*ndf, slab.eta, i, o);
    });
    std::string what = rough_exit ? "rough exit" : "rough entry";
    if (with_internal_reflection) {
      const std::vector<double> halo = halo_averager.Average([&](const model::Vec3& i) {
        return rough_exit ? internal.RoughExit(*ndf, i, o) : internal.RoughEntry(*ndf, i, o);
      });
      double halo_energy = 0.0;
      for (int c = 0; c < grid.num_cells(); ++c) {
        model[c] += halo[c];
        halo_energy += halo[c] * grid.CellSolidAngle(c);
      }
      EXPECT_GT(halo_energy, 0.0);
      what += " + T R R T";
    }
    ExpectAgreement(mc, model, grid, what + ", theta " + std::to_string(theta));
  }
}

TEST(SlabTracer, RoughEntryOnlyMatchesRhoT) { ExpectOneRoughSideAgrees(false, 2); }

TEST(SlabTracer, RoughExitOnlyMatchesRhoB) { ExpectOneRoughSideAgrees(true, 2); }

TEST(SlabTracer, RoughEntryWithFourHitsMatchesRhoTPlusInternalReflection) { ExpectOneRoughSideAgrees(false, 4); }

TEST(SlabTracer, RoughExitWithFourHitsMatchesRhoBPlusInternalReflection) { ExpectOneRoughSideAgrees(true, 4); }

// Both sides rough (the skewed NDF at the entry, GGX at the exit, absorption), a cap of two hits:
// the two-interface integral (model/slab_transmission.h) holds every such path, so it must agree
// with the tracer to MC noise. Its quadrature is made fine here: the formula is under test, the
// default quadrature's accuracy is tested in tests/model/slab_transmission_test.cc.
TEST(SlabTracer, BothRoughWithTwoHitsMatchesTheTwoInterfaceIntegral) {
  const std::unique_ptr<model::Ndf> entry = SkewedNdf(), exit = RoughNdf(0.2);
  Slab slab;
  slab.eta = 1.5;
  slab.entry = SlabInterface::Rough(*entry);
  slab.exit = SlabInterface::Rough(*exit);
  slab.optical_depth = 0.1;
  const SlabTracer tracer(slab);
  const model::SlabTransmission integral(*entry, *exit, slab.eta, slab.optical_depth, {24});
  const model::Hemicube grid(32);
  const CellAverager averager(grid, 2);
  for (double theta : {30.0, 60.0}) {
    const model::Vec3 o = ViewDirection(theta, 20.0);
    SliceOptions options;
    options.paths = 2000000;
    options.max_interactions = 2;
    const BtdfSlice mc = tracer.SliceForView(o, grid, options);
    const model::SlabTransmission::ForViewer view = integral.Viewer(o);
    const std::vector<double> model = averager.Average([&](const model::Vec3& i) { return view.Rho(i); });
    ExpectAgreement(mc, model, grid, "both rough, theta " + std::to_string(theta));
  }
}

// The halo of light reflected inside a slab with both sides rough (the four-hit paths: the
// tracer capped at four hits less the one capped at two) against SlabInternalReflection's shape,
// the one-rough-side terms of both sides summed. Not exact (each term keeps the other side flat),
// so the check is of the shape and its scale: the fit gives it its own weight. Measured (GGX 0.30
// entry, 0.12 exit, 45 degrees, 8M paths): scale 0.87, relative L2 0.21.
TEST(SlabTracer, BothRoughTheFourHitHaloHasTheSlabInternalReflectionsShape) {
  const std::unique_ptr<model::Ndf> entry = RoughNdf(0.30), exit = RoughNdf(0.12);
  Slab slab;
  slab.eta = 1.5;
  slab.entry = SlabInterface::Rough(*entry);
  slab.exit = SlabInterface::Rough(*exit);
  const SlabTracer tracer(slab);
  const model::Hemicube grid(24);
  const model::Vec3 o = ViewDirection(45.0, 20.0);
  SliceOptions options;
  options.paths = 4000000;
  options.max_interactions = 2;
  const BtdfSlice direct = tracer.SliceForView(o, grid, options);
  options.max_interactions = 4;
  const BtdfSlice four = tracer.SliceForView(o, grid, options);
  const model::SlabInternalReflection shape(*entry, *exit, slab.eta);
  const std::vector<double> model = CellAverager(grid, 2).Average([&](const model::Vec3& i) { return shape.Rho(i, o); });
  std::vector<double> halo(grid.num_cells()), solid_angles(grid.num_cells());
  double model_halo = 0, model_model = 0;
  for (int c = 0; c < grid.num_cells(); ++c) {
    halo[c] = four.rho[c] - direct.rho[c];
    solid_angles[c] = grid.CellSolidAngle(c);
    model_halo += solid_angles[c] * model[c] * halo[c];
    model_model += solid_angles[c] * model[c] * model[c];
  }
  const double scale = model_halo / model_model;
  std::vector<double> scaled(model);
  for (double& v : scaled) v *= scale;
  const double error = RelativeL2Error(scaled, halo, solid_angles);
  std::printf("four-hit halo against the shape: scale %.3f, relative L2 %.3f\n", scale, error);
  EXPECT_GT(scale, 0.7);
  EXPECT_LT(scale, 1.1);
  EXPECT_LT(error, 0.3);
}

TEST(SlabTracer, SameSeedGivesTheSameSliceOnAnyNumberOfThreads) {
  Slab slab;
  slab.entry = SlabInterface::Rough(*RoughNdf(0.3));
  slab.exit = SlabInterface::Rough(*SkewedNdf());
  slab.optical_depth = 0.1;
  const SlabTracer tracer(slab);
  const model::Hemicube grid(16);
  SliceOptions options;
  options.paths = 5 * SlabTracer::kChunkPaths + 123;  // a partial last chunk too
  options.seed = 11;
  options.threads = 1;
  const BtdfSlice one = tracer.SliceForView(ViewDirection(35.0), grid, options);
  options.threads = 2;
  const BtdfSlice two = tracer.SliceForView(ViewDirection(35.0), grid, options);
  options.seed = 12;
  const BtdfSlice other_seed = tracer.SliceForView(ViewDirection(35.0), grid, options);
  EXPECT_EQ(one.paths, options.paths);
  EXPECT_EQ(one.rho, two.rho);  // bitwise
  EXPECT_EQ(one.standard_error, two.standard_error);
  EXPECT_EQ(one.fractions.transmitted, two.fractions.transmitted);
  EXPECT_NE(one.rho, other_seed.rho);
}

// Uniform direction in the cone of half-angle `radius` around `axis`, by solid angle.
model::Vec3 SampleCone(const model::Vec3& axis, double radius, common::Pcg32& rng) {
  const double cos_theta = 1.0 - rng.NextDouble() * (1.0 - std::cos(radius));
  const double sin_theta = std::sqrt(std::max(0.0, 1.0 - cos_theta * cos_theta));
  const double phi = model::kTwoPi * rng.NextDouble();
  model::Vec3 t, b;
  model::OrthonormalBasis(axis, &t, &b);
  return cos_theta * axis + sin_theta * (std::cos(phi) * t + std::sin(phi) * b);
}

struct Estimate {
  double mean = 0.0;
  double standard_error = 0.0;
};

// (1 / (Omega_A Omega_B)) integral over cone A of light directions and cone B of view directions
// of rho(i, o), traced from the side of `source` (the cone whose direction is drawn) to `target`
// (the cone the exit direction is binned in). Both cones have half-angle `radius`.
Estimate ConeToCone(const SlabTracer& tracer, const model::Vec3& source_axis, const model::Vec3& target_axis,
                    double radius, int64_t paths, uint64_t seed) {
  const double cone_solid_angle = model::kTwoPi * (1.0 - std::cos(radius));
  const double cos_radius = std::cos(radius);
  common::Pcg32 rng(seed, 0);
  double sum = 0.0;
  double sum_squares = 0.0;
  for (int64_t p = 0; p < paths; ++p) {
    const model::Vec3 source = SampleCone(source_axis, radius, rng);
    const PathRecord path = tracer.TracePath(-source, rng, 100);
    if (!path.transmitted || path.direction.dot(target_axis) < cos_radius) continue;
    const double x = path.energy.transmitted / (std::abs(path.direction.z()) * cone_solid_angle);
    sum += x;
    sum_squares += x * x;
  }
  const double mean = sum / paths;
  return {mean, std::sqrt((sum_squares / paths - mean * mean) / (paths - 1))};
}

// The air-slab-air BTDF is reciprocal, rho(i, o) = rho(o, i) with both directions pointing away:
// tracing from the camera and binning light directions must give the same cone-to-cone average as
// tracing from the light and binning view directions. A skewed NDF on one side, a different one on
// the other and absorption make the two directions of travel genuinely different paths.
TEST(SlabTracer, IsReciprocal) {
  Slab slab;
  slab.entry = SlabInterface::Rough(*SkewedNdf());
  slab.exit = SlabInterface::Rough(*RoughNdf(0.4));
  slab.optical_depth = 0.2;
  const SlabTracer tracer(slab);
  const double radius = 8.0 * model::kPi / 180.0;
  const struct {
    model::Vec3 i, o;
  } pairs[] = {
      {LightDirection(30.0, 180.0), ViewDirection(30.0)},
      {LightDirection(10.0, 200.0), ViewDirection(50.0, 10.0)},
      {LightDirection(55.0, 90.0), ViewDirection(25.0, 250.0)},
  };
  for (const auto& pair : pairs) {
    const Estimate from_camera = ConeToCone(tracer, pair.o, pair.i, radius, 600000, 1);
    const Estimate from_light = ConeToCone(tracer, pair.i, pair.o, radius, 600000, 2);
    const double sigma = std::hypot(from_camera.standard_error, from_light.standard_error);
    EXPECT_GT(from_camera.mean, 20.0 * from_camera.standard_error);  // a lobe, not noise
    EXPECT_NEAR(from_camera.mean, from_light.mean, 4.0 * sigma)
        << "camera-side " << from_camera.mean << " light-side " << from_light.mean;
  }
}

TEST(SlabTracer, StopsOnceTheDominantCellsReachTheTargetError) {
  Slab slab;
  slab.entry = SlabInterface::Rough(*RoughNdf(0.3));
  slab.exit = SlabInterface::Rough(*RoughNdf(0.3));
  const SlabTracer tracer(slab);
  SliceOptions options;
  options.paths = int64_t{1} << 26;
  options.target_relative_error = 0.03;
  const BtdfSlice slice = tracer.SliceForView(ViewDirection(45.0), model::Hemicube(32), options);
  EXPECT_LE(slice.DominantRelativeError(0.9), 0.03);
  EXPECT_LT(slice.paths, options.paths);
  EXPECT_EQ(slice.paths % SlabTracer::kBatchPaths, 0);
}

TEST(SlabTracer, RejectsInvalidInput) {
  Slab slab;
  slab.eta = 1.0;
  EXPECT_THROW(SlabTracer{slab}, common::Error);
  slab.eta = 1.5;
  slab.optical_depth = -1.0;
  EXPECT_THROW(SlabTracer{slab}, common::Error);
  slab.optical_depth = 0.0;
  const SlabTracer tracer(slab);
  EXPECT_THROW(tracer.SliceForView(LightDirection(10.0), model::Hemicube(8), SliceOptions{}), common::Error);
  EXPECT_THROW(tracer.SliceForLight(ViewDirection(10.0), model::Hemicube(8), SliceOptions{}), common::Error);
  EXPECT_THROW(tracer.SliceForView(model::Vec3(0.0, 0.0, 2.0), model::Hemicube(8), SliceOptions{}), common::Error);
}

}  // namespace
}  // namespace svbtdf::simulate
