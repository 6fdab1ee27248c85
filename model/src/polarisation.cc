#include "svbtdf/model/polarisation.h"

#include <algorithm>
#include <cmath>

#include "svbtdf/model/fresnel.h"

namespace svbtdf::model {

TransmittedBeam TransmitPolarised(const Vec3& travel, const Vec3& field, const Vec3& normal, double eta) {
  TransmittedBeam out;
  // The normal on the side the beam goes to.
  const Vec3 n = travel.dot(normal) >= 0.0 ? normal : Vec3(-normal);
  const double cos_i = std::min(1.0, travel.dot(n));
  const double sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
  if (sin2_t >= 1.0) return out;  // totally reflected
  const double cos_t = std::sqrt(1.0 - sin2_t);
  out.valid = true;
  out.travel = ((travel - cos_i * n) / eta + cos_t * n).normalized();
  const FresnelSP r = FresnelDielectricSP(cos_i, eta);
  const double t_s = std::sqrt(std::max(0.0, 1.0 - r.s));
  const double t_p = std::sqrt(std::max(0.0, 1.0 - r.p));
  const Vec3 cross = travel.cross(n);
  const double sin_i = cross.norm();
  if (sin_i < 1e-12) {
    // Normal incidence: s and p are the same (r_s^2 = r_p^2), every field passes alike.
    out.field = t_s * field;
    return out;
  }
  const Vec3 s = cross / sin_i;
  const Vec3 p_in = s.cross(travel);
  const Vec3 p_out = s.cross(out.travel);
  out.field = t_s * field.dot(s) * s + t_p * field.dot(p_in) * p_out;
  return out;
}

Vec3 TransverseField(const Vec3& source_field, const Vec3& travel) {
  const Vec3 e = source_field - source_field.dot(travel) * travel;
  const double length = e.norm();
  return length > 1e-12 ? Vec3(e / length) : Vec3::Zero();
}

double TwoInterfaceTransmittance(const Vec3& travel, const Vec3& field, const Vec3& normal1, double eta1,
                                 const Vec3& normal2, double eta2) {
  const TransmittedBeam first = TransmitPolarised(travel, field, normal1, eta1);
  if (!first.valid) return 0.0;
  const TransmittedBeam second = TransmitPolarised(first.travel, first.field, normal2, eta2);
  return second.valid ? second.field.squaredNorm() : 0.0;
}

double TwoInterfaceTransmittanceUnpolarised(const Vec3& travel, const Vec3& normal1, double eta1,
                                            const Vec3& normal2, double eta2) {
  Vec3 a, b;
  OrthonormalBasis(travel, &a, &b);
  return 0.5 * (TwoInterfaceTransmittance(travel, a, normal1, eta1, normal2, eta2) +
                TwoInterfaceTransmittance(travel, b, normal1, eta1, normal2, eta2));
}

}  // namespace svbtdf::model
