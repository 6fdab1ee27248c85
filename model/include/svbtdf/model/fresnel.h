#pragma once
// Exact Fresnel reflectance of a smooth dielectric interface: unpolarised, and of the s and p
// fields apart (for polarised light, polarisation.h).
//
// Defined here, inline: the dual-microfacet model calls them four times for every evaluation, and
// as out-of-line calls they were 21% of the CPU of a simulated dot image (docs/benchmarks.md,
// "Simulation"); inlined, a simulated dot image renders 1.07-1.10x faster (bench_simulate).

#include <algorithm>
#include <cmath>

namespace svbtdf::model {

// Reflectance for light arriving at an interface whose relative index of refraction is
// eta = n_transmitted / n_incident, with cos_theta_i the cosine between the incident direction
// and the normal on the light's side. A negative cosine means the light arrives from the other
// side: the roles of the media swap (eta -> 1/eta). Returns 1 under total internal reflection.
// Transmittance is 1 - FresnelDielectric(...). (Walter et al. 2007 eq. 22; seed 000 eq. 9.)
inline double FresnelDielectric(double cos_theta_i, double eta);

// Power reflectances of the s (perpendicular) and p (parallel) fields, with the same arguments
// and the same swap of the media for a negative cosine. Both 1 under total internal reflection;
// FresnelDielectric is their mean.
struct FresnelSP {
  double s = 1.0;
  double p = 1.0;
};
inline FresnelSP FresnelDielectricSP(double cos_theta_i, double eta) {
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

inline double FresnelDielectric(double cos_theta_i, double eta) {
  const FresnelSP r = FresnelDielectricSP(cos_theta_i, eta);
  return 0.5 * (r.s + r.p);  // unpolarised light: the mean of two orthogonal linear states
}

}  // namespace svbtdf::model
