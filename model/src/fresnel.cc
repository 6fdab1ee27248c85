#include "svbtdf/model/fresnel.h"

#include <algorithm>
#include <cmath>

namespace svbtdf::model {

FresnelSP FresnelDielectricSP(double cos_theta_i, double eta) {
  cos_theta_i = std::clamp(cos_theta_i, -1.0, 1.0);
  if (cos_theta_i < 0) {
    eta = 1.0 / eta;
    cos_theta_i = -cos_theta_i;
  }
  // Snell: sin_t = sin_i / eta.
  const double sin2_theta_t = (1.0 - cos_theta_i * cos_theta_i) / (eta * eta);
  if (sin2_theta_t >= 1.0) return {1.0, 1.0};
  const double cos_theta_t = std::sqrt(1.0 - sin2_theta_t);
  const double r_parallel = (eta * cos_theta_i - cos_theta_t) / (eta * cos_theta_i + cos_theta_t);
  const double r_perpendicular = (cos_theta_i - eta * cos_theta_t) / (cos_theta_i + eta * cos_theta_t);
  return {r_perpendicular * r_perpendicular, r_parallel * r_parallel};
}

double FresnelDielectric(double cos_theta_i, double eta) {
  const FresnelSP r = FresnelDielectricSP(cos_theta_i, eta);
  return 0.5 * (r.s + r.p);  // unpolarised light: the mean of two orthogonal linear states
}

}  // namespace svbtdf::model
