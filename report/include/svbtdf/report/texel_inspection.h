#pragma once
// Per-texel data of the interactive report (docs/report.md, "The page's data"), precomputed on a
// grid of texels so that the page stays small for any material size:
//
//  - the inspection grid: for each grid texel its BTDF slice as measured (the slice store's
//    samples, luminance; NaN where no valid measurement) and as fitted at the same light
//    directions, and its NDF, fitted and true, as ln D pictures seen from above;
//  - the live view's lobes: each grid texel's transmission lobe fitted by a spherical Gaussian
//    (model/sg_lobe.h, de Rousiers et al. 2012) at five views, for the page's WebGL shader.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "svbtdf/fit/material.h"
#include "svbtdf/fit/slice_store.h"
#include "svbtdf/model/sg_lobe.h"
#include "svbtdf/simulate/truth.h"

namespace svbtdf::report {

// A grid of at most `max_side` x `max_side` texels over a material, evenly spread, at texel centres.
struct TexelGrid {
  int cols = 0, rows = 0;
  std::vector<int> x, y;  // the material texel of grid column c (x[c]) and grid row r (y[r])
};
TexelGrid MakeTexelGrid(int width, int height, int max_side);

// The side of the inspection grid: at most `max_side`, and small enough that grid texels x dots
// stays within `sample_budget` (the page's size grows with both).
int InspectionGridSide(int width, int height, int dots, int max_side, int64_t sample_budget);

// The NDF picture's side (pixels) in the inspection data, and its byte outside the disc.
inline constexpr int kInspectionNdfSide = 16;
inline constexpr uint8_t kNdfOutside = 255;

// The five views at which every lobe is fitted: head-on, then 30 degrees from the normal toward
// +x, +y, -x and -y. The shader blends the lobes of the views nearest its own.
std::vector<model::Vec3> LobeViews();

// A texel's specular transmission at view `o` (toward the camera), k_s rho(i, o) |i.z| over the
// light directions i (z < 0): one spherical Gaussian fitted on luminance (model/sg_lobe.h), in two
// passes (75 degrees around the straight-through direction, then three lobe widths around the
// first fit), stretched into an anisotropic one by the lobe's second moments across its axis
// (the sharpnesses' product stays the fitted one's square), with the lobe's energy per channel.
struct TexelLobe {
  model::SphericalGaussian lobe;               // the isotropic fit (axis, sharpness, amplitude)
  model::Vec3 major = model::Vec3::UnitX();    // across the axis, where the lobe is widest
  double sharpness_major = 1, sharpness_minor = 1;  // along `major` and across it
  std::array<double, 3> energy_rgb{};          // integral of k_s rho |i.z| over the light directions
  double relative_l2 = 0;                      // the isotropic fit's
};
TexelLobe FitTexelLobe(const fit::TexelBtdf& texel, const model::Vec3& o);

// The JSON the page reads. `store` and `truth_parameters` may be null (no measured slice, no
// true NDF); `held_out` are the dots withheld from the fit (marked on the page).
nlohmann::json InspectionData(const fit::Material& material, const fit::SliceStore* store,
                              const simulate::MaterialTruth* truth_parameters, const std::vector<int>& held_out,
                              const TexelGrid& grid, int threads);

// Every texel of `grid`'s lobes at LobeViews(): Float32 records of 11 numbers per view (axis minus
// the straight-through direction -o: 3, major: 3, sharpness along and across it: 2, energy RGB: 3)
// and rho_d (3), base64 in "data".
nlohmann::json LobeData(const fit::Material& material, const TexelGrid& grid, int threads);

}  // namespace svbtdf::report
