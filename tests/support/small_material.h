#pragma once
// Test support: a tiny hand-made material (3x2 texels by default, one GGX representative, constant maps).

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

}  // namespace svbtdf
