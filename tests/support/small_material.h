#pragma once
// Test support: a tiny hand-made material (3x2 texels by default, one GGX representative, constant maps).

#include <algorithm>
#include <vector>

#include "svbtdf/fit/material.h"
#include "svbtdf/model/ggx.h"

namespace svbtdf {

// A width x height material (at least 5 texels) with one representative (a GGX table, texel 4)
// and constant maps.
inline fit::Material SmallMaterial(int width = 3, int height = 2) {
  fit::Material m;
  m.width = width;
  m.height = height;
  m.eta = 1.45;
  m.ndf_resolution = 16;
  model::TabulatedNdf ndf(model::Hemicube(16), model::GgxNdf(0.25, 0.18));
  ndf.Normalize();
  m.representative_texels = {4};
  m.representative_ln_d = {ndf.ln_d()};
  m.alpha = common::FloatImage(width, height, 1, 0.6f);
  m.shadowing_roughness = common::FloatImage(width, height, 1, 0.2f);
  m.k_s = common::FloatImage(width, height, 3, 0.8f);
  m.rho_d = common::FloatImage(width, height, 3, 0.02f);
  m.residual = common::FloatImage(width, height, 1, -1.0f);
  m.cluster = common::FloatImage(width, height, 1, 0.0f);
  m.weight_index = common::FloatImage(width, height, 1, 0.0f);
  m.weight_value = common::FloatImage(width, height, 1, 1.0f);
  return m;
}

// A material of regions_x x regions_y square regions of `region` texels a side, region r (row-major)
// holding one GGX lobe (alphas[r], anisotropy * alphas[r]) tabulated at `ndf_resolution`, every
// texel weight 1 on its region's representative; `texel_m` metres a texel. For the export tests:
// a sample whose roughness changes across it.
inline fit::Material RegionsMaterial(int regions_x, int regions_y, int region, const std::vector<double>& alphas,
                                     double anisotropy = 1.0, double texel_m = 0.002, int ndf_resolution = 16) {
  // SmallMaterial's constant maps (alpha, shadowing, k_s, rho_d, one weight channel), new NDFs.
  fit::Material m = SmallMaterial(regions_x * region, regions_y * region);
  m.width_m = m.width * texel_m;
  m.height_m = m.height * texel_m;
  m.eta = 1.5;
  m.ndf_resolution = ndf_resolution;
  const model::Hemicube grid(ndf_resolution);
  m.representative_texels.clear();
  m.representative_ln_d.clear();
  for (int r = 0; r < regions_x * regions_y; ++r) {
    model::TabulatedNdf ndf(grid, model::GgxNdf(alphas.at(r), anisotropy * alphas.at(r)));
    ndf.Normalize();
    m.representative_ln_d.push_back(ndf.ln_d());
    m.representative_texels.push_back(static_cast<int64_t>((r / regions_x) * region) * m.width + (r % regions_x) * region);
  }
  for (int y = 0; y < m.height; ++y) {
    for (int x = 0; x < m.width; ++x) {
      const int r = (y / region) * regions_x + x / region;
      m.cluster.at(x, y) = static_cast<float>(r);
      m.weight_index.at(x, y) = static_cast<float>(r);
    }
  }
  return m;
}

// After the paper's grid sheet (simulate's `grid-sheet` pattern), made directly in the material
// format: a side x side material whose texels hold an anisotropic GGX lobe (0.40 along x, 0.05
// along y) inside the grid's cells and the same lobe turned a quarter (0.05, 0.40) on its lines,
// every `period` texels, with a texel either side of a line blending the two (weights 0.5): two
// crossed ellipses, which no ellipse fits. NDF resolution 32, `texel_m` metres a texel.
inline fit::Material GridSheetLikeMaterial(int side, int period = 8, double texel_m = 0.0005) {
  fit::Material m = RegionsMaterial(1, 1, side, {0.1}, 1.0, texel_m, 32);
  const model::Hemicube grid(32);
  m.representative_ln_d.clear();
  for (const model::GgxNdf& lobe : {model::GgxNdf(0.40, 0.05), model::GgxNdf(0.05, 0.40)}) {
    model::TabulatedNdf ndf(grid, lobe);
    ndf.Normalize();
    m.representative_ln_d.push_back(ndf.ln_d());
  }
  m.representative_texels = {static_cast<int64_t>(period / 2) * side + period / 2, 0};
  m.weight_index = common::FloatImage(side, side, 2);
  m.weight_value = common::FloatImage(side, side, 2);
  const auto distance_to_line = [&](int i) { return std::min(i % period, period - i % period); };
  for (int y = 0; y < side; ++y) {
    for (int x = 0; x < side; ++x) {
      const int d = std::min(distance_to_line(x), distance_to_line(y));
      const float on_line = d == 0 ? 1.0f : d == 1 ? 0.5f : 0.0f;
      m.weight_index.at(x, y, 0) = 0, m.weight_value.at(x, y, 0) = 1.0f - on_line;
      m.weight_index.at(x, y, 1) = 1, m.weight_value.at(x, y, 1) = on_line;
      m.cluster.at(x, y) = on_line > 0.5f ? 1.0f : 0.0f;
    }
  }
  return m;
}

}  // namespace svbtdf
