#pragma once
// Test support: a material built exactly from an analytic simulator truth, so that comparing it
// with that truth isolates whatever a test changes afterwards.

#include "svbtdf/fit/material.h"
#include "svbtdf/model/tabulated_ndf.h"
#include "svbtdf/simulate/truth_io.h"

namespace svbtdf {

// Every texel its own representative, with the truth's NDF tabulated at resolution 32.
inline fit::Material MaterialFromTruth(const simulate::MaterialTruth& truth) {
  fit::Material m;
  m.width = truth.width();
  m.height = truth.height();
  m.eta = truth.eta;
  m.ndf_resolution = 32;
  const model::Hemicube grid(m.ndf_resolution);
  m.alpha = truth.alpha;
  m.shadowing_roughness = truth.shadowing_roughness;
  m.k_s = truth.k_s;
  m.rho_d = truth.rho_d;
  m.residual = common::FloatImage(m.width, m.height, 1, 0.0f);
  m.cluster = common::FloatImage(m.width, m.height, 1);
  m.weight_index = common::FloatImage(m.width, m.height, 1);
  m.weight_value = common::FloatImage(m.width, m.height, 1, 1.0f);
  for (int y = 0; y < m.height; ++y) {
    for (int x = 0; x < m.width; ++x) {
      model::TabulatedNdf ndf(grid, *truth.TexelNdf(x, y));
      ndf.Normalize();
      const int index = static_cast<int>(m.representative_texels.size());
      m.representative_texels.push_back(static_cast<int64_t>(y) * m.width + x);
      m.representative_ln_d.push_back(ndf.ln_d());
      m.cluster.at(x, y) = static_cast<float>(index);
      m.weight_index.at(x, y) = static_cast<float>(index);
    }
  }
  return m;
}

}  // namespace svbtdf
