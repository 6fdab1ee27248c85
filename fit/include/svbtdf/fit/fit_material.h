#pragma once
// Fitting a whole processed session (paper Secs. 4.2-4.3; docs/fitting.md): cluster the texels'
// resampled slices, fit the dual-microfacet model at the representatives only, and express every
// texel as an affine combination of nearby representatives, whose alpha and k_s are then refined
// against the texel's own samples.
//
// Long fits are resumable: every finished representative is appended (fsync'ed) to a checkpoint
// journal, and a rerun with the same options skips the representatives it already holds.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "svbtdf/fit/material.h"
#include "svbtdf/fit/slice_store.h"
#include "svbtdf/fit/standard_error_options.h"

namespace svbtdf::fit {

struct FitMaterialOptions {
  MaterialModel model = MaterialModel::kDualMicrofacet;  // or the baseline (`--model ggx`)
  double eta = 0.0;                       // 0: the store's nominal eta (an error when unknown)
  double representative_fraction = 0.01;  // the paper's 1%; >= 1 fits every valid texel
  int ndf_resolution = 32;
  double holdout = 0.0;                   // fraction of the dots withheld from the fit (random, seeded)
  uint64_t seed = 1;
  int threads = 0;
  bool progress = true;
  std::filesystem::path checkpoint;       // journal of finished fits; empty: none
  // Fit alpha, k_s and (interpolated texels) the weights of every texel to its own samples, the
  // representatives' NDF tables held fixed (refine_texels.h); false keeps the paper's plain
  // interpolation and the representatives' alpha by its eq. 18.
  bool refine_texels = true;
  // TexelFitOptions::free_horizon for the dual-microfacet fits: on by default here (rice-paper's
  // NDF error 17.9% -> 3.7%, docs/fitting.md); false is the paper's fixed horizon.
  bool free_horizon = true;
  // TexelFitOptions::secant_alternations (`--secant-alternations`): alpha's alternations reach
  // their fixed point instead of stopping short of it (docs/fitting.md, step 3). Off by default.
  bool secant_alternations = false;
  // Per-texel standard errors (docs/fitting.md, "Uncertainty"): the *_se maps of material format
  // version 3. false writes a material without them (version 1), as before.
  bool uncertainty = true;
  StandardErrorOptions standard_errors;  // how they are estimated
  // Dual-microfacet: fit and write the light reflected inside the slab as part of every texel's
  // rho (TexelFitOptions::internal_reflection; material format version 4).
  bool internal_reflection = false;
  // Slab: fit each side's anisotropy too (SlabFitOptions::anisotropic; `--anisotropic-sides`).
  bool slab_anisotropic = false;
};

// A representative whose fit fails (kNumerical) takes the fit of the nearest one that succeeded
// and is listed in the provenance. Throws svbtdf::Error(kInvalidInput) for bad options,
// kNumerical when no representative can be fitted, kInterrupted when interrupted (the
// checkpoint then holds the finished fits).
Material FitMaterial(const SliceStore& store, const FitMaterialOptions& options);

// The fraction of texels fitted as representatives, from "all" or a fraction in (0, 1] as the
// user wrote it (`--representatives`); svbtdf::Error(kInvalidInput) naming `subject` otherwise.
double ParseRepresentativeFraction(const std::string& text, const std::string& subject = "--representatives");

// The dots withheld by `holdout` with `seed` (sorted), as recorded in the material's provenance.
std::vector<int> HeldOutDots(int num_dots, double holdout, uint64_t seed);

// For every texel of a width x height grid (row-major), the index into `sources` (texel indices)
// of the source nearest to it in Euclidean distance; ties go to either. A masked-out texel takes
// the clustering weights of the nearest valid texel. Exact, in time linear in the texels (the
// distance transform of Felzenszwalb and Huttenlocher 2012, keeping the nearest source), where
// comparing every texel with every source grows with their product: a 2000 x 2000 session with
// a tenth of its texels masked would compare 1.4e12 pairs. Throws svbtdf::Error(kInvalidInput)
// for no sources or a source outside the grid.
std::vector<int64_t> NearestSources(int width, int height, const std::vector<int64_t>& sources);

// Whose fit each representative (a texel index on the width x height grid) takes: its own, or,
// where `failed` says its own fit failed, that of the nearest representative whose fit succeeded
// (NearestSources). Throws svbtdf::Error(kInvalidInput) when none succeeded (FitMaterial has
// stopped before then), a representative is outside the grid or the lengths differ.
std::vector<int> LendersOfFits(const std::vector<int64_t>& representatives, int width, int height,
                               const std::vector<uint8_t>& failed);

}  // namespace svbtdf::fit
