#pragma once
// Refining the fitted texels against their own samples (docs/fitting.md, step 6).
//
// After clustering, a texel that was not fitted takes its representatives' blended parameters
// (paper Sec. 4.3). Its own samples are still at hand, and a few parameters are cheap to fit to
// them: the blend weight alpha (golden-section search on [0, 1], each step with the best scale in
// closed form), the transmission scale k_s (linear least squares, per channel) and, for the
// dual-microfacet model, the weights over the same representatives (by Levenberg-Marquardt with
// alpha, extrapolating where the texel lies outside their hull; kept only where they lower the
// texel's residual). The representatives' NDF tables and the shadowing roughness stay as fitted,
// so the material format does not change. This costs about 2 ms per texel instead of the full
// fit's 0.2 s, and removes most of the error that interpolating between few representatives adds.
// The representatives themselves get the same alpha and k_s search with their fitted NDF: the
// paper's alpha criterion (eq. 18) is not the residual, and the search lowers the residual.

#include <cstdint>
#include <optional>
#include <vector>

#include "svbtdf/fit/material.h"
#include "svbtdf/fit/slice_store.h"
#include "svbtdf/fit/standard_error_options.h"

namespace svbtdf::fit {

struct RefineOptions {
  bool refine_alpha = true;        // false: k_s only (the walter-ggx baseline has no alpha)
  bool refit_weights = true;       // dual-microfacet: refit the weights over the representatives
  double alpha_tolerance = 0.004;  // golden-section bracket width at which the search stops
  // Standard errors of alpha, k_s, rho_d, the NDF width and the prediction (docs/fitting.md,
  // "Uncertainty"), written to the material's *_se maps when it has them.
  bool uncertainty = true;
  StandardErrorOptions standard_errors;  // how they are estimated
  int threads = 0;                 // 0: all hardware threads
  bool progress = false;
};

struct RefineStatistics {
  int64_t representatives = 0;        // representatives refined (alpha and k_s)
  int64_t texels = 0;                 // interpolated texels refined
  double median_rmse_blended = 0.0;   // their median relative RMSE on their own samples, before ...
  double median_rmse_refined = 0.0;   // ... and after the refinement
};

// Refines `texels` (indices y * width + x) of `material` in place against their samples in
// `store` on the dots with use_dot[q] (empty: all): first the representatives among them (alpha
// and k_s, with their fitted NDF; dual-microfacet only), then the interpolated ones. Writes alpha,
// k_s, the refitted weights and the texel's residual (relative RMSE on its own samples). A texel
// without usable samples keeps the blend. Throws svbtdf::Error(kInvalidInput) when the store and
// the material disagree in size, kInterrupted when interrupted.
RefineStatistics RefineTexels(const SliceStore& store, const std::vector<bool>& use_dot,
                              const std::vector<int64_t>& texels, const RefineOptions& options, Material* material);

}  // namespace svbtdf::fit
