// Recovery tests of the per-texel dual-microfacet fit: slices synthesised from the model with a
// known NDF, alpha, shadowing and scale, seen through the paper's rig geometry, must be recovered
// within the tolerances of issue 5.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "svbtdf/common/error.h"
#include "svbtdf/fit/quality.h"
#include "svbtdf/fit/texel_fit.h"
#include "svbtdf/model/dual_microfacet.h"
#include "svbtdf/model/ggx.h"
#include "svbtdf/model/ndf_factory.h"
#include "svbtdf/model/tabulated_ndf.h"
#include "svbtdf/simulate/slab_tracer.h"
#include "synthetic_slices.h"

namespace svbtdf::fit {
namespace {

// Relative L2 error of the normalised NDF over the cells the data constrain (those whose centre
// is the half vector of a bright sample's configuration, or next to one), weighted by solid angle.
double NdfRelativeL2(const model::Hemicube& grid, const model::TabulatedNdf& fitted, const model::TabulatedNdf& truth,
                     const TexelSlice& slice, double eta) {
  const model::DualMicrofacetModel model(eta);
  double brightest = 0;
  for (double r : slice.rho) brightest = std::max(brightest, r);
  std::vector<bool> constrained(grid.num_cells(), false);
  for (size_t k = 0; k < slice.light.size(); ++k) {
    if (slice.rho[k] < 0.05 * brightest) continue;
    for (const model::VirtualConfiguration& c : {model.RoughEntry(slice.light[k], slice.view), model.RoughExit(slice.light[k], slice.view)}) {
      if (c.valid) constrained[grid.CellOf(c.h)] = true;
    }
  }
  double error = 0, norm = 0;
  int cells = 0;
  for (int c = 0; c < grid.num_cells(); ++c) {
    if (!constrained[c]) continue;
    const model::Vec3 h = grid.CellCenter(c);
    error += model::Square(fitted.D(h) - truth.D(h)) * grid.CellSolidAngle(c);
    norm += model::Square(truth.D(h)) * grid.CellSolidAngle(c);
    ++cells;
  }
  EXPECT_GT(cells, 20);
  return std::sqrt(error / norm);
}

double HeldOutRelativeRmse(const FittedTexel& fitted, const Truth& truth, const model::Vec3& view) {
  const RigSamples held_out = DotGrid(view, 40, 0.5);
  double error = 0, norm = 0;
  for (const model::Vec3& i : held_out.light) {
    const double expected = truth.Rho(i, view);
    error += model::Square(fitted.Rho(i, view) - expected);
    norm += model::Square(expected);
  }
  return std::sqrt(error / norm);
}

class TexelFitRecovery : public ::testing::TestWithParam<double> {};

TEST_P(TexelFitRecovery, RecoversAlphaNdfAndHeldOutBtdfWithOnePercentNoise) {
  const double true_alpha = GetParam();
  const TexelFitter fitter(1.5);
  const model::GgxNdf analytic(0.25, 0.15);
  const Truth truth = MakeTruth(fitter.ndf_grid(), analytic, true_alpha);
  const model::Vec3 view = model::SphericalDirection(model::kPi / 4, 0.0);
  const TexelSlice slice = Synthesize(truth, view, DotGrid(view, 40, 0.0), 0.01, 42);

  const TexelFitResult fit = fitter.Fit(slice);
  std::printf("alpha %.3f (truth %.2f) k_s %.3f shadowing %.3f log_rms %.4f rel_rmse %.4f alternations %d used %d\n", fit.alpha, true_alpha, fit.k_s, fit.shadowing_roughness, fit.log_rms, fit.relative_rmse, fit.alternations, fit.samples_used);
  EXPECT_NEAR(fit.alpha, true_alpha, 0.05);
  const FittedTexel model = fitter.Model(fit);
  EXPECT_LT(NdfRelativeL2(fitter.ndf_grid(), model.ndf(), *truth.ndf, slice, 1.5), 0.10);
  EXPECT_LT(HeldOutRelativeRmse(model, truth, view), 0.05);
  EXPECT_LT(fit.relative_rmse, 0.05);
  EXPECT_NEAR(fit.k_s, truth.k_s, 0.1 * truth.k_s);
}

INSTANTIATE_TEST_SUITE_P(Alphas, TexelFitRecovery, ::testing::Values(0.15, 0.5, 0.8));

// The shadowing roughness's standard error holds the truth over independent noise draws of one
// texel. With one view, G trades against a free tabulated D: the fit barely leaves its start
// (0.2; a truth of 0.3 comes out 0.21, with the same residual as a start of 0.3, which comes out
// 0.30), so its error bar must say how little the data pin it. The shadowing fit's own sandwich
// (D held fixed) held the 0.3 truth on 0 of 40 draws (median |error| / se 3.1); with the profile
// over the ln D system added (docs/fitting.md, "Uncertainty"), on 39 of 40 (median 1.8: wide
// enough, but the error is the start's bias, not noise).
TEST(TexelFit, ShadowingRoughnessErrorBarsHoldTheTruthAcrossNoiseDraws) {
  const TexelFitter fitter(1.5);
  const model::GgxNdf analytic(0.25, 0.15);
  const model::Vec3 view = model::SphericalDirection(model::kPi / 4, 0.0);
  constexpr int kDraws = 25;
  for (double true_shadowing : {0.2, 0.3}) {
    Truth truth = MakeTruth(fitter.ndf_grid(), analytic, 0.5);
    truth.shadowing_roughness = true_shadowing;
    int covered = 0;
    std::vector<double> z, se;
    for (int draw = 0; draw < kDraws; ++draw) {
      const TexelFitResult fit = fitter.Fit(Synthesize(truth, view, DotGrid(view, 20, 0.0), 0.01, 1000 + draw));
      ASSERT_GT(fit.shadowing_roughness_se, 0.0);
      se.push_back(fit.shadowing_roughness_se);
      z.push_back(std::abs(fit.shadowing_roughness - true_shadowing) / fit.shadowing_roughness_se);
      covered += z.back() <= 2.0;
    }
    std::sort(z.begin(), z.end());
    std::sort(se.begin(), se.end());
    std::printf("shadowing %.2f: truth within 2 se on %d of %d draws, median |error| / se %.2f, median se %.3f\n",
                true_shadowing, covered, kDraws, z[kDraws / 2], se[kDraws / 2]);
    EXPECT_GE(covered, kDraws - 2) << true_shadowing;
    EXPECT_LT(se[kDraws / 2], 0.1) << "an error bar this wide says nothing";  // measured 0.047-0.050
  }
}

TEST(TexelFit, RejectsMalformedSlices) {
  const TexelFitter fitter(1.5);
  TexelSlice slice;
  slice.view = model::SphericalDirection(0.5, 0.0);
  slice.light = {model::FlipZ(model::SphericalDirection(0.2, 0.0))};
  EXPECT_THROW(fitter.Fit(slice), common::Error);  // rho missing
  slice.rho = {1.0};
  EXPECT_THROW(fitter.Fit(slice), common::Error);  // too few samples
  slice.light = {model::SphericalDirection(0.2, 0.0)};
  EXPECT_THROW(fitter.Fit(slice), common::Error);  // light on the camera side
  EXPECT_THROW(TexelFitter(1.0), common::Error);
}

TEST(TexelFit, SymbolicAnalysisIsSharedAcrossTexelsOfOneView) {
  const TexelFitter fitter(1.5);
  const model::Vec3 view = model::SphericalDirection(model::kPi / 4, 0.0);
  const RigSamples rig = DotGrid(view, 24, 0.0);
  FitWorkspace workspace;
  for (double roughness : {0.15, 0.2, 0.3}) {
    const Truth truth = MakeTruth(fitter.ndf_grid(), model::GgxNdf(roughness), 0.5);
    fitter.Fit(Synthesize(truth, view, rig, 0.0, 1), &workspace);
  }
  EXPECT_GE(workspace.factorizations(), 6);  // each texel's first system and its final pass
  EXPECT_LT(workspace.symbolic_analyses(), workspace.factorizations());
}

// With `secant_alternations` the alternations reach the fixed point of alpha's criterion
// (docs/fitting.md, step 3). For rough lobes seen at 45 degrees the paper's plain steps contract
// slowly (each 0.6-0.7 of the last), and stopping at the first step below the tolerance leaves
// alpha short of the fixed point, towards its start of 0.5: 0.772 after 7 alternations for a
// truth of 0.8 at roughness 0.4, where the fixed point is 0.798 (30 plain alternations to 1e-6),
// and 0.2026 / 0.2006 / 0.7915 in the other three cases. The secant steps stop within 0.001 of
// it in 4-5 alternations (measured).
TEST(TexelFit, SecantAlternationsReachTheCriterionsFixedPoint) {
  TexelFitOptions secant_options, converged_options;
  secant_options.secant_alternations = true;
  converged_options.alpha_tolerance = 1e-6;
  converged_options.max_alternations = 200;
  const TexelFitter fitter(1.5, secant_options), converged(1.5, converged_options);
  const model::Vec3 view = model::SphericalDirection(model::kPi / 4, 0.0);
  const RigSamples rig = DotGrid(view, 40, 0.0);
  for (const double roughness : {0.3, 0.4}) {
    for (const double alpha : {0.2, 0.8}) {
      SCOPED_TRACE(testing::Message() << "roughness " << roughness << ", alpha " << alpha);
      const Truth truth = MakeTruth(fitter.ndf_grid(), model::GgxNdf(roughness), alpha);
      const TexelSlice slice = Synthesize(truth, view, rig, 0.01, 7);
      const TexelFitResult fit = fitter.Fit(slice), reference = converged.Fit(slice);
      std::printf("roughness %.1f alpha %.1f: %.4f in %d alternations, converged %.4f in %d\n", roughness, alpha,
                  fit.alpha, fit.alternations, reference.alpha, reference.alternations);
      EXPECT_NEAR(fit.alpha, reference.alpha, 0.002);
      EXPECT_NEAR(fit.alpha, alpha, 0.005);
      EXPECT_LT(fit.alternations, reference.alternations);
    }
  }
}

// The alternations' systems solved by conjugate gradients (preconditioned with the last
// factorisation) give the fit that factorising every system gives, with fewer factorisations.
TEST(TexelFit, IterativeSolvesAgreeWithFactorisingEverySystem) {
  TexelFitOptions direct_options;
  direct_options.iterative_solves = false;
  const TexelFitter iterative(1.5), direct(1.5, direct_options);
  const model::Vec3 view = model::SphericalDirection(model::kPi / 5, 0.3);
  const RigSamples rig = DotGrid(view, 24, 0.0);
  FitWorkspace iterative_workspace, direct_workspace;
  for (const auto& [roughness, alpha] : {std::pair{0.12, 0.3}, {0.25, 0.6}, {0.4, 0.8}}) {
    SCOPED_TRACE(roughness);
    const Truth truth = MakeTruth(iterative.ndf_grid(), model::GgxNdf(roughness), alpha);
    const TexelSlice slice = Synthesize(truth, view, rig, 0.01, 7);
    const TexelFitResult a = iterative.Fit(slice, &iterative_workspace);
    const TexelFitResult b = direct.Fit(slice, &direct_workspace);
    EXPECT_EQ(a.alternations, b.alternations);
    EXPECT_NEAR(a.alpha, b.alpha, 1e-7);
    EXPECT_NEAR(a.k_s / b.k_s, 1.0, 1e-7);
    EXPECT_NEAR(a.shadowing_roughness, b.shadowing_roughness, 1e-6);
    ASSERT_EQ(a.ln_d.size(), b.ln_d.size());
    double largest = 0;
    for (size_t c = 0; c < a.ln_d.size(); ++c) largest = std::max(largest, std::abs(a.ln_d[c] - b.ln_d[c]));
    EXPECT_LT(largest, 1e-6);
    EXPECT_NEAR(a.ndf_width_se / b.ndf_width_se, 1.0, 1e-6);
    EXPECT_NEAR(a.alpha_profile_se / b.alpha_profile_se, 1.0, 1e-6);
  }
  EXPECT_EQ(direct_workspace.iterative_solves(), 0);
  EXPECT_GT(iterative_workspace.iterative_solves(), 0);
  EXPECT_LT(iterative_workspace.factorizations(), direct_workspace.factorizations());
}

// A slab whose light is partly reflected inside it (the T R R T paths of a rough lobe): the fit
// with the term recovers the truth as closely as the plain fit recovers a truth without it (held
// out: 0.58% against 0.53%, 2026-12-05), the dual-microfacet terms alone cannot (1.19%).
TEST(TexelFit, InternalReflectionTermIsFittedWhereTheSlabHasIt) {
  TexelFitOptions with_options;
  with_options.internal_reflection = true;
  const TexelFitter without(1.5), with(1.5, with_options);
  Truth truth = MakeTruth(without.ndf_grid(), model::GgxNdf(0.35), 0.8);
  truth.internal_reflection = true;
  const model::Vec3 view = model::SphericalDirection(model::kPi / 4, 0.0);
  const TexelSlice slice = Synthesize(truth, view, DotGrid(view, 24, 0.0), 0.01, 5);
  const TexelFitResult a = without.Fit(slice), b = with.Fit(slice);
  const double error_without = HeldOutRelativeRmse(without.Model(a), truth, view);
  const double error_with = HeldOutRelativeRmse(with.Model(b), truth, view);
  std::printf("held-out without %.4f with %.4f; alpha %.3f / %.3f (truth %.2f); k_s %.3f / %.3f (truth %.2f)\n",
              error_without, error_with, a.alpha, b.alpha, truth.alpha, a.k_s, b.k_s, truth.k_s);
  EXPECT_LT(error_with, 0.6 * error_without);
  EXPECT_LT(error_with, 0.01);
  EXPECT_NEAR(b.alpha, truth.alpha, 0.05);
  EXPECT_NEAR(b.k_s, truth.k_s, 0.05 * truth.k_s);
  // The fit's own residual is measured against the samples with the term included.
  EXPECT_LT(b.relative_rmse, a.relative_rmse);
}

// A traced two-interface slab (the Monte Carlo truth's "frosted" slab: GGX 0.30 entry, 0.12 exit,
// every path), tabulated as `small`'s truth is (a 16-cell hemicube), seen at 30 degrees and read
// at a 20 x 20 dot grid. It is outside the dual-microfacet family, and with the horizon free the
// fit moved the table's mass where no dot looks: k_s above 1e3 (as on half of `small`'s Monte
// Carlo representatives). The fitter must then fit it again with the paper's fixed horizon, say
// so, and return exactly that fit (measured: k_s 18, relative RMSE 0.066, 2026-12-06), with the
// internal-reflection term's refits too.
TEST(TexelFit, AFreeHorizonWhoseScaleEscapesIsFittedFixedInstead) {
  const model::GgxNdf entry(0.30), exit(0.12);
  simulate::Slab slab;
  slab.eta = 1.5;
  slab.entry = simulate::SlabInterface::Rough(entry);
  slab.exit = simulate::SlabInterface::Rough(exit);
  const model::Vec3 view = model::SphericalDirection(model::kPi / 6, -model::kPi / 2);
  const model::Hemicube table(16);
  simulate::SliceOptions trace;
  trace.paths = 1 << 20;
  trace.seed = 3;
  const simulate::BtdfSlice traced = simulate::SlabTracer(slab).SliceForView(view, table, trace);
  const RigSamples dots = DotGrid(view, 20, 0.0);
  TexelSlice slice;
  slice.view = view;
  slice.solid_angle = dots.solid_angle;
  slice.light = dots.light;
  for (const model::Vec3& i : dots.light) slice.rho.push_back(traced.rho[table.CellOf(model::FlipZ(i))]);
  TexelFitOptions free_options;
  free_options.free_horizon = true;
  const TexelFitResult free = TexelFitter(slab.eta, free_options).Fit(slice);
  const TexelFitResult fixed = TexelFitter(slab.eta).Fit(slice);
  std::printf("free horizon: k_s %.3g, fixed instead %d, rmse %.4f; fixed: k_s %.3g, rmse %.4f\n", free.k_s,
              free.horizon_fixed_instead, free.relative_rmse, fixed.k_s, fixed.relative_rmse);
  EXPECT_TRUE(free.horizon_fixed_instead);
  EXPECT_FALSE(fixed.horizon_fixed_instead);
  EXPECT_LE(free.k_s, kMaxPlausibleKs);
  EXPECT_EQ(free.k_s, fixed.k_s);
  EXPECT_EQ(free.ln_d, fixed.ln_d);
  // With the internal-reflection term's refits the texel stays on the fixed horizon it fell back to.
  free_options.internal_reflection = true;
  TexelFitOptions fixed_with_term;
  fixed_with_term.internal_reflection = true;
  const TexelFitResult free_term = TexelFitter(slab.eta, free_options).Fit(slice);
  const TexelFitResult fixed_term = TexelFitter(slab.eta, fixed_with_term).Fit(slice);
  EXPECT_TRUE(free_term.horizon_fixed_instead);
  EXPECT_EQ(free_term.ln_d, fixed_term.ln_d);
}

}  // namespace
}  // namespace svbtdf::fit
