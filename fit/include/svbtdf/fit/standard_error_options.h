#pragma once
// How the fit estimates its per-texel standard errors (docs/fitting.md, "Uncertainty"). The
// defaults are the ones docs/validation.md ("Per-texel uncertainty") settled on; the switches
// are there to measure what each part adds.

namespace svbtdf::fit {

struct StandardErrorOptions {
  // How far (in dot spacings) a fit's residuals count as correlated in the sandwich covariance
  // (Newey-West): a misfit spans the lobe, several dots; noise does not reach past one. 0 treats
  // every residual as independent.
  double correlation_radius = 3.0;
  // Add the model error: the distance between each interpolated texel's two fits (to alpha, k_s
  // and the NDF width) and the floor samples' offset from the store's rho_d (to rho_d's).
  bool model_error = true;
  // The texels around each texel on the grid whose model-error draws are averaged: 1 is the
  // 3 x 3 window, 0 each texel's own draw (an error bar from one draw has heavy tails).
  int model_error_pool_radius = 1;
};

}  // namespace svbtdf::fit
