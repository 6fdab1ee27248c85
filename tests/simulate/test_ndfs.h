#pragma once
// NDFs shared by the simulate tests.
#include <memory>

#include "svbtdf/model/ndf_factory.h"

namespace svbtdf::simulate {

inline std::unique_ptr<model::Ndf> RoughNdf(double roughness) {
  model::AnalyticNdfParams p;
  p.alpha_x = p.alpha_y = roughness;
  return model::MakeAnalyticNdf("ggx", p);
}

// A skewed, rotated, anisotropic Ellipsoid NDF: no symmetry for a sign error to hide behind.
inline std::unique_ptr<model::Ndf> SkewedNdf() {
  model::AnalyticNdfParams p;
  p.alpha_x = 0.3;
  p.alpha_y = 0.18;
  p.theta_x = 0.2;
  p.theta_y = -0.15;
  p.theta_z = 0.5;
  return model::MakeAnalyticNdf("ellipsoid", p);
}

// The paper's Fig. 5 uses a Gaussian (Beckmann) NDF.
inline std::unique_ptr<model::Ndf> PaperNdf(double roughness) {
  model::AnalyticNdfParams p;
  p.alpha_x = p.alpha_y = roughness;
  return model::MakeAnalyticNdf("beckmann", p);
}

}  // namespace svbtdf::simulate
