// Tests of the slab fit (fit/slab_fit.h): recovery of both interfaces' roughnesses from slices of
// the model itself and from the Monte Carlo slab (two interface hits: the paths the model holds,
// and every path: what a real slab sends), and honest standard errors.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <random>

#include "svbtdf/common/error.h"
#include "svbtdf/fit/slab_fit.h"
#include "svbtdf/model/ggx.h"
#include "svbtdf/model/hemicube.h"
#include "svbtdf/simulate/slab_tracer.h"
#include "synthetic_slices.h"

namespace svbtdf::fit {
namespace {

const model::Vec3 kView = model::SphericalDirection(model::kPi / 4, 0.0);  // the paper's 45 degrees

TexelSlice ModelSlice(const SlabInterfaces& truth, double k_s, double eta, int dots_per_side, double noise, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const RigSamples rig = DotGrid(kView, dots_per_side, 0.0);
  TexelSlice slice;
  slice.view = kView;
  slice.light = rig.light;
  slice.solid_angle = rig.solid_angle;
  for (const model::Vec3& i : rig.light) slice.rho.push_back(k_s * SlabShape(truth, eta, i, kView) * (1.0 + noise * gauss(rng)));
  return slice;
}

TEST(SlabFit, RecoversBothRoughnessesOfASlabItCanRepresent) {
  const double eta = 1.5;
  const SlabFitter fitter(eta);
  struct Case {
    SlabInterfaces truth;
  };
  for (const SlabInterfaces& truth : {SlabInterfaces{0.30, 0.12}, SlabInterfaces{0.12, 0.30}, SlabInterfaces{0.2, 0.2}}) {
    const TexelSlice slice = ModelSlice(truth, 0.85, eta, 20, 0.01, 3);
    const SlabFitResult fit = fitter.Fit(slice);
    std::printf("truth %.2f / %.2f: fitted %.4f +- %.4f / %.4f +- %.4f (correlation %.2f), k_s %.4f, internal "
                "reflection %.3f, log rms %.4f\n", truth.entry_roughness, truth.exit_roughness,
                fit.interfaces.entry_roughness, fit.entry_roughness_se, fit.interfaces.exit_roughness,
                fit.exit_roughness_se, fit.roughness_correlation, fit.k_s, fit.interfaces.internal_reflection, fit.log_rms);
    EXPECT_TRUE(fit.converged);
    EXPECT_NEAR(fit.interfaces.entry_roughness / truth.entry_roughness, 1.0, 0.05);
    EXPECT_NEAR(fit.interfaces.exit_roughness / truth.exit_roughness, 1.0, 0.05);
    EXPECT_NEAR(fit.k_s / 0.85, 1.0, 0.05);
    // The noise is 1%: the fit reaches it, and the truth lies within 3 standard errors.
    EXPECT_LT(fit.log_rms, 0.015);
    EXPECT_GT(fit.entry_roughness_se, 0.0);
    EXPECT_GT(fit.exit_roughness_se, 0.0);
    EXPECT_LT(std::abs(fit.interfaces.entry_roughness - truth.entry_roughness), 3.0 * fit.entry_roughness_se);
    EXPECT_LT(std::abs(fit.interfaces.exit_roughness - truth.exit_roughness), 3.0 * fit.exit_roughness_se);
  }
}

// The dots at the cells of a traced slice: every cell with enough paths in the dots' cone.
TexelSlice TracedSlice(const simulate::Slab& slab, int max_interactions, uint64_t seed) {
  const simulate::SlabTracer tracer(slab);
  const model::Hemicube grid(48);
  simulate::SliceOptions options;
  options.paths = 4000000;
  options.max_interactions = max_interactions;
  options.seed = seed;
  const simulate::BtdfSlice mc = tracer.SliceForView(kView, grid, options);
  TexelSlice slice;
  slice.view = kView;
  const model::Vec3 straight_through = -kView;
  for (int c = 0; c < grid.num_cells(); ++c) {
    const model::Vec3 i = model::FlipZ(grid.CellCenter(c));
    // The monitor of the paper's rig spans about 50 degrees about the straight-through direction.
    if (mc.hits[c] < 400 || i.dot(straight_through) < std::cos(0.45)) continue;
    slice.light.push_back(i);
    slice.rho.push_back(mc.rho[c]);
  }
  return slice;
}

simulate::Slab GgxSlab(double entry, double exit, double eta, std::unique_ptr<model::Ndf>* keep_entry,
                       std::unique_ptr<model::Ndf>* keep_exit) {
  *keep_entry = std::make_unique<model::GgxNdf>(entry);
  *keep_exit = std::make_unique<model::GgxNdf>(exit);
  simulate::Slab slab;
  slab.eta = eta;
  slab.entry = simulate::SlabInterface::Rough(**keep_entry);
  slab.exit = simulate::SlabInterface::Rough(**keep_exit);
  return slab;
}

// A traced slab with GGX 0.30 at the entry and 0.12 at the exit (the Monte Carlo truth's
// "frosted" slab). With two interface hits the model holds every path, so the fit must find both
// roughnesses to within the cell averaging of the slice (a 48-resolution hemicube, about 2
// degrees) and its noise. With every path, the light reflected inside the slab (6% of what it
// transmits at 45 degrees) adds a broad halo, which the fit's internal-reflection term takes;
// without the term the fit widens the exit to reach it.
TEST(SlabFit, RecoversTheRoughnessesOfATracedSlab) {
  std::unique_ptr<model::Ndf> entry, exit;
  const simulate::Slab slab = GgxSlab(0.30, 0.12, 1.5, &entry, &exit);
  SlabFitOptions without_term;
  without_term.internal_reflection = false;
  const SlabFitter fitter(slab.eta), direct_only(slab.eta, without_term);
  const TexelSlice two_hits = TracedSlice(slab, 2, 5), every_path = TracedSlice(slab, 100, 5);
  const auto print = [](const char* what, const SlabFitResult& fit) {
    std::printf("%s: entry %.4f +- %.4f, exit %.4f +- %.4f (correlation %.2f), k_s %.4f, internal reflection %.3f, "
                "relative RMSE %.4f\n", what, fit.interfaces.entry_roughness, fit.entry_roughness_se,
                fit.interfaces.exit_roughness, fit.exit_roughness_se, fit.roughness_correlation, fit.k_s,
                fit.interfaces.internal_reflection, fit.relative_rmse);
  };
  const SlabFitResult direct = fitter.Fit(two_hits);
  print("two hits", direct);
  EXPECT_NEAR(direct.interfaces.entry_roughness / 0.30, 1.0, 0.05);
  EXPECT_NEAR(direct.interfaces.exit_roughness / 0.12, 1.0, 0.05);
  EXPECT_NEAR(direct.k_s, 1.0, 0.03);
  EXPECT_LT(direct.interfaces.internal_reflection, 0.2);  // no halo to find (every path is there: 1.5)
  // Measured: entry 0.300, exit 0.122 (+1.4%) with the term; 0.297 and 0.131 (+9%) without.
  const SlabFitResult with_term = fitter.Fit(every_path), without = direct_only.Fit(every_path);
  print("every path", with_term);
  print("every path, no internal reflection", without);
  EXPECT_NEAR(with_term.interfaces.entry_roughness / 0.30, 1.0, 0.05);
  EXPECT_NEAR(with_term.interfaces.exit_roughness / 0.12, 1.0, 0.05);
  EXPECT_GT(with_term.interfaces.internal_reflection, 0.5);
  EXPECT_LT(with_term.relative_rmse, without.relative_rmse);
  EXPECT_LT(std::abs(with_term.interfaces.exit_roughness / 0.12 - 1), std::abs(without.interfaces.exit_roughness / 0.12 - 1));
}

TEST(SlabFit, RefusesASliceWithTooFewBrightSamples) {
  const SlabFitter fitter(1.5);
  TexelSlice slice;
  slice.view = kView;
  for (int k = 0; k < 5; ++k) {
    slice.light.push_back(model::FlipZ(model::SphericalDirection(0.1 * k, 0.0)));
    slice.rho.push_back(1.0);
  }
  EXPECT_THROW(fitter.Fit(slice), common::Error);
  EXPECT_THROW(SlabFitter(0.9), common::Error);
}

}  // namespace
}  // namespace svbtdf::fit
