#pragma once
// Test support: a tiny hand-made material (3x2 texels by default, one GGX representative, constant maps).

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
  fit::Material m;
  m.width = regions_x * region;
  m.height = regions_y * region;
  m.width_m = m.width * texel_m;
  m.height_m = m.height * texel_m;
  m.eta = 1.5;
  m.ndf_resolution = ndf_resolution;
  const model::Hemicube grid(ndf_resolution);
  for (int r = 0; r < regions_x * regions_y; ++r) {
    model::TabulatedNdf ndf(grid, model::GgxNdf(alphas.at(r), anisotropy * alphas.at(r)));
    ndf.Normalize();
    m.representative_ln_d.push_back(ndf.ln_d());
    m.representative_texels.push_back(static_cast<int64_t>((r / regions_x) * region) * m.width + (r % regions_x) * region);
  }
  m.alpha = common::FloatImage(m.width, m.height, 1, 0.6f);
  m.shadowing_roughness = common::FloatImage(m.width, m.height, 1, 0.0f);
  m.k_s = common::FloatImage(m.width, m.height, 3, 0.85f);
  m.rho_d = common::FloatImage(m.width, m.height, 3, 0.005f);
  m.residual = common::FloatImage(m.width, m.height, 1, -1.0f);
  m.cluster = common::FloatImage(m.width, m.height, 1, 0.0f);
  m.weight_index = common::FloatImage(m.width, m.height, 1, 0.0f);
  m.weight_value = common::FloatImage(m.width, m.height, 1, 1.0f);
  for (int y = 0; y < m.height; ++y) {
    for (int x = 0; x < m.width; ++x) {
      const int r = (y / region) * regions_x + x / region;
      m.cluster.at(x, y) = static_cast<float>(r);
      m.weight_index.at(x, y) = static_cast<float>(r);
    }
  }
  return m;
}

}  // namespace svbtdf
