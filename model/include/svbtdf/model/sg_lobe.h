#pragma once
// A spherical-Gaussian approximation of a BTDF slice (de Rousiers, Bousseau, Subr, Holzschuch and
// Ramamoorthi 2012): G(d) = a exp(lambda (mu.d - 1)). Three numbers per texel give a fast preview
// of a fitted material's refraction lobe.

#include <vector>

#include "svbtdf/model/vec.h"

namespace svbtdf::model {

struct SphericalGaussian {
  Vec3 axis = Vec3::UnitZ();  // mu, unit
  double sharpness = 1.0;     // lambda > 0
  double amplitude = 0.0;     // a >= 0
  double operator()(const Vec3& d) const { return amplitude * std::exp(sharpness * (axis.dot(d) - 1.0)); }
};

struct SphericalGaussianFit {
  SphericalGaussian lobe;
  double relative_l2 = 0.0;  // sqrt(sum w (G - f)^2 / sum w f^2)
  int iterations = 0;
};

// Fits a lobe to samples f(d_k) >= 0 weighted by w_k (e.g. solid angles): initialised from the
// weighted mean direction (axis and, through its length, sharpness) and refined by
// Levenberg-Marquardt on the weighted squared error. Throws svbtdf::Error(kInvalidInput) for
// mismatched sizes or a slice without positive values.
SphericalGaussianFit FitSphericalGaussian(const std::vector<Vec3>& directions, const std::vector<double>& values,
                                          const std::vector<double>& weights);

}  // namespace svbtdf::model
