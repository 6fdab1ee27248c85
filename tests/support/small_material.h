#pragma once
// Test support: a tiny hand-made material (3x2 texels, one GGX representative, constant maps).

#include "svbtdf/fit/material.h"
#include "svbtdf/model/ggx.h"

namespace svbtdf {

// A 3x2 material with one representative (a GGX table) and constant maps.
inline fit::Material SmallMaterial() {
  fit::Material m;
  m.width = 3;
  m.height = 2;
  m.eta = 1.45;
  m.ndf_resolution = 16;
  TabulatedNdf ndf(Hemicube(16), GgxNdf(0.25, 0.18));
  ndf.Normalize();
  m.representative_texels = {4};
  m.representative_ln_d = {ndf.ln_d()};
  m.alpha = FloatImage(3, 2, 1, 0.6f);
  m.shadowing_roughness = FloatImage(3, 2, 1, 0.2f);
  m.k_s = FloatImage(3, 2, 3, 0.8f);
  m.rho_d = FloatImage(3, 2, 3, 0.02f);
  m.residual = FloatImage(3, 2, 1, -1.0f);
  m.cluster = FloatImage(3, 2, 1, 0.0f);
  m.weight_index = FloatImage(3, 2, 1, 0.0f);
  m.weight_value = FloatImage(3, 2, 1, 1.0f);
  return m;
}

}  // namespace svbtdf
