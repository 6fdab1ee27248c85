#include "svbtdf/model/ggx.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "svbtdf/model/ndf_validation.h"

namespace svbtdf::model {

GgxNdf::GgxNdf(double alpha_x, double alpha_y) : alpha_x_(alpha_x), alpha_y_(alpha_y) {
  RequirePositiveRoughness("ggx", alpha_x, alpha_y);
}

double GgxNdf::D(const Vec3& h) const {
  if (h.z() <= 0) return 0.0;
  const double e = Square(h.x() / alpha_x_) + Square(h.y() / alpha_y_) + Square(h.z());
  return 1.0 / (kPi * alpha_x_ * alpha_y_ * e * e);
}

double GgxNdf::Lambda(const Vec3& v) const {
  const double vz2 = v.z() * v.z();
  if (vz2 <= 0) return std::numeric_limits<double>::infinity();
  const double a2_tan2 = (Square(alpha_x_ * v.x()) + Square(alpha_y_ * v.y())) / vz2;
  return 0.5 * (std::sqrt(1.0 + a2_tan2) - 1.0);
}

double GgxNdf::G1(const Vec3& v, const Vec3& h) const {
  const Vec3 side_adjusted = v.z() < 0 ? Vec3(-v) : v;
  if (side_adjusted.dot(h) <= 0 || side_adjusted.z() <= 0) return 0.0;
  return 1.0 / (1.0 + Lambda(side_adjusted));
}

NormalSample GgxNdf::SampleVisibleNormal(const Vec3& v, const Vec2& u) const {
  // In the stretched space the visible normals of the unit hemisphere seen from v_h are uniform
  // on the spherical cap {c : c.z >= -v_h.z} shifted by v_h.
  const Vec3 v_h = Vec3(alpha_x_ * v.x(), alpha_y_ * v.y(), v.z()).normalized();
  const double phi = kTwoPi * u.x();
  const double z = std::fma(1.0 - u.y(), 1.0 + v_h.z(), -v_h.z());
  const double sin_theta = std::sqrt(std::clamp(1.0 - z * z, 0.0, 1.0));
  const Vec3 n_h = Vec3(sin_theta * std::cos(phi), sin_theta * std::sin(phi), z) + v_h;
  const Vec3 h = Vec3(alpha_x_ * n_h.x(), alpha_y_ * n_h.y(), std::max(1e-12, n_h.z())).normalized();
  return {h, VisibleNormalPdf(v, h), 1.0};
}

double GgxNdf::VisibleNormalPdf(const Vec3& v, const Vec3& h) const {
  if (v.z() <= 0) return 0.0;
  return G1(v, h) * std::max(0.0, v.dot(h)) * D(h) / v.z();
}

}  // namespace svbtdf::model
