#pragma once
// Diffuse separation (docs/slice-store.md, "Diffuse separation"): the floor rho_d of a texel's
// samples, under shot noise, whatever the refractive lobe on top of it.

#include <array>
#include <vector>

#include "svbtdf/model/dual_microfacet.h"
#include "svbtdf/model/vec.h"

namespace svbtdf::process {

// The diffuse term of one texel from samples R_q = k_s lobe_q + rho_d + noise_q (docs/slice-store.md,
// "Diffuse separation"). `noise_scale[q]` is s_q = |p_q - x|^2 / (|i_q.z| P(theta_q)), the factor
// that turns the camera's rate into R: under shot noise Var(R_q) = c s_q E[R_q] with one unknown c
// per texel. `neighbours[q]` are the samples of two dots on either side of q's on the grid
// ({-1, -1}: none): the lobe is smooth from dot to dot and the noise is not, so the median of the
// second differences R_q - (R_a + R_b) / 2 over the floor set measures c whatever the lobe.
// The floor is the set of samples within `clip` standard deviations (sqrt(c floor s_q)) of its
// inverse-variance weighted mean, found by iterating from the lowest tenth of the samples;
// symmetric clipping keeps the mean unbiased for symmetric noise, where the paper's minimum
// (eq. 14) takes the most negative noise draw. Selection is on luminance; each channel is the
// weighted mean over the set.
struct DiffuseEstimate {
  model::Rgb rho_d = {0, 0, 0};
  int floor_samples = 0;  // samples in the floor set
  double spread = 0.0;    // the noise's standard deviation on the floor, in units of sqrt(s_q)
};
DiffuseEstimate EstimateDiffuse(const std::vector<model::Rgb>& r, const std::vector<double>& noise_scale,
                                const std::vector<std::array<int, 2>>& neighbours, double clip = 2.5);
// For every dot, two dots on either side of it along one of the grid's directions (the nearest
// dot and the one at its mirror image), or {-1, -1} when the grid has none (its corners).
std::vector<std::array<int, 2>> OppositeNeighbours(const std::vector<model::Vec3>& dots);

}  // namespace svbtdf::process
