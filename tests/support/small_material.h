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
  TabulatedNdf ndf(Hemicube(16), GgxNdf(0.25, 0.18));
  ndf.Normalize();
  m.representative_texels = {4};
  m.representative_ln_d = {ndf.ln_d()};
  m.alpha = FloatImage(width, height, 1, 0.6f);
  m.shadowing_roughness = FloatImage(width, height, 1, 0.2f);
  m.k_s = FloatImage(width, height, 3, 0.8f);
  m.rho_d = FloatImage(width, height, 3, 0.02f);
  m.residual = FloatImage(width, height, 1, -1.0f);
  m.cluster = FloatImage(width, height, 1, 0.0f);
  m.weight_index = FloatImage(width, height, 1, 0.0f);
  m.weight_value = FloatImage(width, height, 1, 1.0f);
  return m;
}

}  // namespace svbtdf
