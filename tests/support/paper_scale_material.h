#pragma once
// Test and benchmark support: a synthetic material at the paper's scale, as a fit of a 600 x 600
// sample would make it: `representatives` GGX tables (alphas 0.1-0.4 on each axis, seeded) at
// the NDF resolution 32, every texel an affine blend of 4 of them (weights 0.4, 0.3, 0.2, 0.1),
// sized 8 cm. Used by bench_render and bench_export.

#include <random>

#include "svbtdf/fit/material.h"
#include "svbtdf/model/ggx.h"

namespace svbtdf {

inline fit::Material PaperScaleMaterial(int side, int representatives) {
  fit::Material m;
  m.width = m.height = side;
  m.eta = 1.5;
  m.width_m = m.height_m = 0.08;
  m.ndf_resolution = 32;
  const model::Hemicube grid(m.ndf_resolution);
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(0, 1);
  for (int r = 0; r < representatives; ++r) {
    model::TabulatedNdf table(grid, model::GgxNdf(0.1 + 0.3 * u(rng), 0.1 + 0.3 * u(rng)));
    table.Normalize();
    m.representative_ln_d.push_back(table.ln_d());
    m.representative_texels.push_back(static_cast<int64_t>(u(rng) * side * side));
  }
  m.alpha = common::FloatImage(side, side, 1, 0.5f);
  m.shadowing_roughness = common::FloatImage(side, side, 1, 0.2f);
  m.k_s = common::FloatImage(side, side, 3, 0.9f);
  m.rho_d = common::FloatImage(side, side, 3, 0.01f);
  m.residual = common::FloatImage(side, side, 1, 0.0f);
  m.cluster = common::FloatImage(side, side, 1, 0.0f);
  m.weight_index = common::FloatImage(side, side, 4);
  m.weight_value = common::FloatImage(side, side, 4);
  for (int y = 0; y < side; ++y) {
    for (int x = 0; x < side; ++x) {
      const double weights[4] = {0.4, 0.3, 0.2, 0.1};
      for (int k = 0; k < 4; ++k) {
        m.weight_index.at(x, y, k) = static_cast<float>(static_cast<int>(u(rng) * representatives) % representatives);
        m.weight_value.at(x, y, k) = static_cast<float>(weights[k]);
      }
    }
  }
  return m;
}

}  // namespace svbtdf
