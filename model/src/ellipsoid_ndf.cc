#include "svbtdf/model/ellipsoid_ndf.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "svbtdf/common/error.h"
#include "svbtdf/model/ndf_validation.h"

namespace svbtdf::model {

EllipsoidNdf::EllipsoidNdf(double alpha_x, double alpha_y, double theta_x, double theta_y, double theta_z) {
  RequirePositiveRoughness("ellipsoid", alpha_x, alpha_y);
  for (const double angle : {theta_x, theta_y, theta_z}) {
    if (!std::isfinite(angle)) common::ThrowInvalidInput("ellipsoid angles", "must be finite numbers (radians)");
  }
  const Mat3 s = Vec3(alpha_x, alpha_y, 1.0).asDiagonal();
  const Mat3 r = (Eigen::AngleAxisd(theta_x, Vec3::UnitX()) * Eigen::AngleAxisd(theta_y, Vec3::UnitY()) *
                  Eigen::AngleAxisd(theta_z, Vec3::UnitZ()))
                     .toRotationMatrix();
  a_ = s * r;
  a_inv_t_ = a_.inverse().transpose();
  det_a_ = std::abs(a_.determinant());
  a_n_ = a_ * Vec3::UnitZ();
  a_n_norm_ = a_n_.norm();
}

double EllipsoidNdf::D(const Vec3& m) const {
  if (m.z() <= 0) return 0.0;
  const double k = (a_inv_t_ * m).squaredNorm();
  return 1.0 / (kPi * det_a_ * a_n_norm_ * k * k);
}

double EllipsoidNdf::AreaRatio(const Vec3& u) const {
  const Vec3 a_u = a_ * u;
  return 2.0 * a_n_norm_ * a_n_norm_ / (a_u.norm() * a_n_norm_ + a_u.dot(a_n_));
}

double EllipsoidNdf::G1(const Vec3& v, const Vec3& m) const {
  const Vec3 u = v.z() < 0 ? Vec3(-v) : v;
  if (u.dot(m) <= 0 || u.z() <= 0) return 0.0;
  return std::min(1.0, AreaRatio(u) * u.z());
}

double EllipsoidNdf::VisibleNormalPdf(const Vec3& v, const Vec3& m) const {
  if (v.z() <= 0) return 0.0;
  return std::max(0.0, v.dot(m)) * D(m) * AreaRatio(v);
}

NormalSample EllipsoidNdf::SampleVisibleNormal(const Vec3& v, const Vec2& u) const {
  // Sphere space: view and "up" directions.
  const Vec3 view_s = (a_ * v).normalized();
  const Vec3 up_s = a_n_ / a_n_norm_;
  Vec3 t, b;
  OrthonormalBasis(up_s, &t, &b);
  const Vec3 view_local(view_s.dot(t), view_s.dot(b), view_s.dot(up_s));
  // Visible normals of the unit upper hemisphere seen from view_local: uniform on the spherical
  // cap {c : c.z >= -view.z} shifted by the view direction (Dupuy and Benyoub 2023).
  const double phi = kTwoPi * u.x();
  const double z = std::fma(1.0 - u.y(), 1.0 + view_local.z(), -view_local.z());
  const double sin_theta = std::sqrt(std::clamp(1.0 - z * z, 0.0, 1.0));
  const Vec3 h_local = Vec3(sin_theta * std::cos(phi), sin_theta * std::sin(phi), z) + view_local;
  const Vec3 m_s = (h_local.x() * t + h_local.y() * b + h_local.z() * up_s).normalized();
  Vec3 m = (a_.transpose() * m_s).normalized();
  if (m.z() <= 0) m = Vec3(m.x(), m.y(), 1e-12).normalized();  // on the boundary, by rounding
  const double pdf = VisibleNormalPdf(v, m);
  const double k = AreaRatio(v) * v.z();
  return {m, pdf, std::min(1.0, k) / k};
}

}  // namespace svbtdf::model
