#pragma once
// Exact unpolarised Fresnel reflectance of a smooth dielectric interface.

namespace svbtdf::model {

// Reflectance for light arriving at an interface whose relative index of refraction is
// eta = n_transmitted / n_incident, with cos_theta_i the cosine between the incident direction
// and the normal on the light's side. A negative cosine means the light arrives from the other
// side: the roles of the media swap (eta -> 1/eta). Returns 1 under total internal reflection.
// Transmittance is 1 - FresnelDielectric(...). (Walter et al. 2007 eq. 22; seed 000 eq. 9.)
double FresnelDielectric(double cos_theta_i, double eta);

}  // namespace svbtdf::model
