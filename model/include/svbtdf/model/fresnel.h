#pragma once
// Exact Fresnel reflectance of a smooth dielectric interface: unpolarised, and of the s and p
// fields apart (for polarised light, polarisation.h).

namespace svbtdf::model {

// Reflectance for light arriving at an interface whose relative index of refraction is
// eta = n_transmitted / n_incident, with cos_theta_i the cosine between the incident direction
// and the normal on the light's side. A negative cosine means the light arrives from the other
// side: the roles of the media swap (eta -> 1/eta). Returns 1 under total internal reflection.
// Transmittance is 1 - FresnelDielectric(...). (Walter et al. 2007 eq. 22; seed 000 eq. 9.)
double FresnelDielectric(double cos_theta_i, double eta);

// Power reflectances of the s (perpendicular) and p (parallel) fields, with the same arguments
// and the same swap of the media for a negative cosine. Both 1 under total internal reflection;
// FresnelDielectric is their mean.
struct FresnelSP {
  double s = 1.0;
  double p = 1.0;
};
FresnelSP FresnelDielectricSP(double cos_theta_i, double eta);

}  // namespace svbtdf::model
