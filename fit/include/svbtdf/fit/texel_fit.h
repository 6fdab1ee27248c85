#pragma once
// Fitting the dual-microfacet model to one texel's measured BTDF slice (Dai et al. 2009,
// Sec. 4.2; docs/fitting.md). The unknowns are ln D over an NDF hemicube and the blend weight
// alpha; the shadowing roughness and the transmission scale are refined afterwards.
//
//   1. For fixed alpha, ln D solves a sparse linear least-squares problem: one data row per
//      sample, alpha ln D(h_T) + (1 - alpha) ln D(h_B) = ln rho - alpha ln A_T - (1 - alpha) ln A_B,
//      with ln D(h) the bilinear interpolation of the cell unknowns (so the rows stay linear),
//      Laplacian smoothness rows, horizon cells fixed at ln(1e-6), and in the first pass polar
//      symmetry rows ln D(h) = ln D(-h.x, -h.y, h.z).
//   2. For fixed D, alpha minimises the distance between the BTDF-weighted mean incident
//      directions of the measured and the model slice (paper eq. 18), by golden-section search.
//   3. Alternate from alpha = 0.5 until alpha moves less than 0.01 (optionally by secant steps
//      towards the fixed point of steps 1-2), then solve D once more with weak symmetry rows and
//      normalise it (projected integral 1; the scale goes into k_s).
//   4. Refine the Smith shadowing roughness (and the scale) with Ceres' Levenberg-Marquardt on the
//      log residuals (paper eq. 15) with D and alpha fixed.
//   5. Optionally (`internal_reflection`), the light reflected once by each interface inside the
//      slab (model/internal_reflection.h) is part of the model: it is quadratic in D, so it is
//      taken out of the samples with the last fit's D, alpha and k_s and steps 1-4 run again
//      (a fixed-point iteration; docs/fitting.md, "Light reflected inside the slab").

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "svbtdf/fit/standard_error_options.h"
#include "svbtdf/model/dual_microfacet.h"
#include "svbtdf/model/hemicube.h"
#include "svbtdf/model/tabulated_ndf.h"
#include "svbtdf/model/shadowing.h"
#include "svbtdf/model/vec.h"

namespace svbtdf::fit {

// One texel's measured refractive BTDF slice (the diffuse part rho_d already removed).
struct TexelSlice {
  model::Vec3 view = model::Vec3::UnitZ();        // o: unit, o.z > 0
  std::vector<model::Vec3> light;          // i_k: unit, i_k.z < 0
  std::vector<double> rho;          // luminance rho(i_k, o) >= 0
  std::vector<double> solid_angle;  // solid angle each sample stands for (eq. 18 weights); empty: equal
  std::vector<double> weight;       // confidence of each sample, 0 drops it; empty: all 1
  std::vector<std::array<double, 3>> rho_rgb;  // optional per-channel values, for k_s per channel
  // Optional: the full measured R per channel, diffuse included and not clipped at zero (the
  // store's samples), from which the refinement measures rho_d's standard error.
  std::vector<std::array<double, 3>> measured_rgb;
  std::vector<int> dot;  // optional: the store's dot index q of each sample
};

struct TexelFitOptions {
  int ndf_resolution = 32;          // the paper's 32x32 top face
  double smoothness_weight = 0.3;   // weight of the rows 4 x_h - sum of its 4 neighbours = 0
  double symmetry_weight = 1.0;     // weight of the first-pass rows x_h - x_mirror(h) = 0
  // Relative weight of the symmetry rows in the final pass. The paper drops them (0), but with one
  // view the data cannot tell how D is split between the h_T and h_B regions (a null space of
  // the log-blend rows); a weak prior picks the most symmetric of the equivalent solutions and
  // keeps D's normalisation, and so k_s, right (docs/fitting.md).
  double final_symmetry_weight = 0.1;
  double horizon_ln_d = -13.815510557964274;  // ln(1e-6): the paper's value at the NDF's horizon
  // true: the horizon cells are unknowns like the others, set by the smoothness rows (and any
  // data) instead of held at horizon_ln_d. A rough lobe (GGX roughness above about 0.3) keeps
  // much of its mass near the horizon, which the paper's 1e-6 pulls down through the smoothness
  // rows: on a synthetic rice-paper-like material the NDF error falls from 21% to 11.5%
  // (docs/validation.md). Where the free fit's k_s comes out implausible (above
  // kMaxPlausibleKs, quality.h: the table's mass went where no dot looks), the texel is fitted
  // again with the horizon fixed (TexelFitResult::horizon_fixed_instead). Off here, the paper's
  // solver; FitMaterialOptions turns it on.
  bool free_horizon = false;
  double dark_fraction = 2e-3;      // samples below this fraction of the slice maximum are too
                                    // dark for their logarithm to mean anything: dropped from (1)
  double initial_alpha = 0.5;
  double alpha_tolerance = 0.01;    // the alternations stop when their step is below this
  int max_alternations = 12;
  // true: from the second alternation on, a secant step on g(alpha) - alpha (g: steps 1-2) where
  // g's slope is at most 0.75, instead of the paper's plain step alpha = g(alpha), which stops
  // short of the fixed point, towards the start, by up to 3 times the tolerance for rough lobes.
  // Measured better on alpha, its error bars and held-out error (docs/fitting.md, step 3), but
  // off: with it the internal-reflection term no longer improves the held-out error of
  // FitMaterialTest's slab (not yet understood).
  bool secant_alternations = false;
  // true: the alternations' ln D systems after a texel's first are solved by conjugate gradients
  // preconditioned with the last factorisation (a median of 14 iterations instead of one
  // factorisation each; the solutions agree to 1e-9). false: every system is factorised, the
  // reference for tests.
  bool iterative_solves = true;
  double initial_shadowing_roughness = 0.2;
  bool refine_shadowing = true;
  // Standard errors (docs/fitting.md, "Uncertainty"): of the shadowing roughness and the NDF
  // width, and alpha's profile (two more sparse solves).
  bool profile_uncertainty = true;
  StandardErrorOptions standard_errors;  // the shadowing fit's: its correlation_radius
  // Step 5: rho = rho_dual + IR (DualMicrofacetParams::internal_reflection), with this many
  // refits after the first (each evaluates the term at every sample: about 0.4 ms a sample).
  bool internal_reflection = false;
  int internal_reflection_passes = 2;
};

struct TexelFitResult {
  double alpha = 0.5;
  double shadowing_roughness = 0.2;
  double k_s = 1.0;                      // luminance scale of the refractive part
  std::array<double, 3> k_s_rgb = {1.0, 1.0, 1.0};
  std::vector<double> ln_d;              // per NDF hemicube cell; D normalised to projected integral 1
  double log_rms = 0.0;                  // RMS of the ln rho residuals over the samples used
  double relative_rmse = 0.0;            // sqrt(sum (model - rho)^2 / sum rho^2) over all samples
  int alternations = 0;
  int samples_used = 0;
  bool horizon_fixed_instead = false;    // free_horizon's fit left k_s implausible: fitted fixed
  // Standard errors (docs/fitting.md, "Uncertainty"); -1 where not known.
  double shadowing_roughness_se = -1.0;  // the sandwich covariance of the shadowing fit (step 4)
  double ndf_width = -1.0;               // NdfWidth of the fitted table (ndf_error.h)
  double ndf_width_se = -1.0;            // from the final ln D system's normal equations
  double alpha_profile_se = -1.0;        // alpha's, from the profile of the final pass over alpha (D free)
  double k_s_profile_relative_se = -1.0; // what that adds to k_s, relative
};

// Reusable per-thread state: the sparse Cholesky factorisation whose symbolic analysis is shared
// by every texel whose normal-equation pattern matches the previous one, and whose numeric
// factorisation preconditions the solves of the next alternations and texels.
class FitWorkspace {
 public:
  FitWorkspace();
  ~FitWorkspace();
  FitWorkspace(FitWorkspace&&) noexcept;
  FitWorkspace& operator=(FitWorkspace&&) noexcept;

  int64_t factorizations() const;
  int64_t symbolic_analyses() const;
  int64_t iterative_solves() const;  // solves by conjugate gradients preconditioned with an older factorisation

  struct State;  // the solver and its analysed pattern (texel_fit.cc)

 private:
  friend class TexelFitter;
  std::unique_ptr<State> state_;
};

// A fitted texel as an evaluable BTDF: luminance rho(i, o) = k_s rho_dual(i, o; D, alpha, G), plus
// k_s IR(i, o; D, alpha) with `internal_reflection`.
class FittedTexel {
 public:
  FittedTexel(const model::Hemicube& grid, double eta, const TexelFitResult& fit, bool internal_reflection = false);
  double Rho(const model::Vec3& i, const model::Vec3& o) const;
  const model::TabulatedNdf& ndf() const { return *ndf_; }

 private:
  std::shared_ptr<const model::TabulatedNdf> ndf_;
  model::DualMicrofacetParams params_;  // eta, alpha, shadowing and the term; k_s = 1
  double k_s_;
};

class TexelFitter {
 public:
  // Throws svbtdf::Error(kInvalidInput) for eta <= 1 or bad options.
  TexelFitter(double eta, const TexelFitOptions& options = {});

  const model::Hemicube& ndf_grid() const { return grid_; }
  double eta() const { return eta_; }
  const TexelFitOptions& options() const { return options_; }

  // Throws svbtdf::Error(kInvalidInput) when the slice is malformed (sizes, directions) and
  // kNumerical when it holds too few usable samples to constrain a fit.
  TexelFitResult Fit(const TexelSlice& slice, FitWorkspace* workspace = nullptr) const;

  // The fitted model, ready to evaluate at many direction pairs.
  FittedTexel Model(const TexelFitResult& fit) const;

 private:
  struct GridSystem;  // the rows that do not depend on the data, built once per fitter

  std::shared_ptr<const GridSystem> BuildGridSystem(bool free_horizon) const;

  // Steps 1-4: the dual-microfacet terms alone, on the ln D system `system`.
  TexelFitResult FitDualTerms(const TexelSlice& slice, const GridSystem& system, FitWorkspace* workspace) const;
  // The same on *system, and again on the fixed horizon's system (which *system then becomes) when
  // a free horizon leaves k_s implausible.
  TexelFitResult FitDualTermsOrFixHorizon(const TexelSlice& slice, const GridSystem** system,
                                          FitWorkspace* workspace) const;

  double eta_;
  TexelFitOptions options_;
  model::Hemicube grid_;
  std::shared_ptr<const GridSystem> system_;
  std::shared_ptr<const GridSystem> fixed_horizon_system_;  // only with free_horizon
};

// `slice` with the light reflected inside the slab taken out of its values: the term of `ndf`
// blended with `alpha` (model::InternalReflection), times k_s per channel (`k_s` for the
// luminance). What is left is what the dual-microfacet terms alone have to fit; a value the term
// exceeds becomes negative and too dark to fit (TexelFitOptions::dark_fraction).
TexelSlice WithoutInternalReflection(const TexelSlice& slice, const model::Ndf& ndf, double eta, double alpha,
                                     double k_s, const std::array<double, 3>& k_s_rgb);

}  // namespace svbtdf::fit
