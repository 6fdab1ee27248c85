#pragma once
// The Ellipsoid NDF of Walter, Dong, Marschner and Greenberg (2014/2016): the normal distribution
// of an ellipsoid {p : |A p| = C} restricted to the upper half (m.n > 0), normalised by the
// projected area. A = S R with S = diag(alpha_x, alpha_y, 1) and R = Rx(theta_x) Ry(theta_y)
// Rz(theta_z): theta_z turns the anisotropy in the plane, theta_x and theta_y skew the lobe off the
// normal. With theta_x = theta_y = 0 it is anisotropic GGX rotated by theta_z.

#include "svbtdf/model/ndf.h"

namespace svbtdf::model {

class EllipsoidNdf final : public Ndf {
 public:
  // Throws svbtdf::Error(kInvalidInput) for non-positive or non-finite roughness or angles.
  EllipsoidNdf(double alpha_x, double alpha_y, double theta_x, double theta_y, double theta_z);

  const Mat3& shape() const { return a_; }

  std::string name() const override { return "ellipsoid"; }
  // D(m) = chi+(m.n) / (pi |A| |A n| |A^-T m|^4)   (their eq. 1)
  double D(const Vec3& m) const override;
  // G1(u, m) = min(1, 2 |An|^2 |u.n| / (|Au| |An| + Au.An)) chi+(u.m), u side-adjusted (eqs. 6-7).
  double G1(const Vec3& v, const Vec3& m) const override;
  // Exact sampling of the visible lune: in the sphere space q = A p the visible upper half is the
  // part of the unit sphere with m_s.(A u) > 0 and m_s.(A n) > 0; it is sampled uniformly in
  // projected area (the spherical-cap method of Dupuy and Benyoub 2023 in the frame of A n), and
  // m = normalize(A^T m_s). pdf = (u.m) D(m) A_e(n) / A_l(u, n); weight = min(1, k) / k <= 1 with
  // k = A_e(n) |u.n| / A_l(u, n).
  NormalSample SampleVisibleNormal(const Vec3& v, const Vec2& u) const override;
  double VisibleNormalPdf(const Vec3& v, const Vec3& m) const override;
  std::unique_ptr<Ndf> Clone() const override { return std::make_unique<EllipsoidNdf>(*this); }

 private:
  // A_e(n) / A_l(u, n) for a unit u with u.n > 0.
  double AreaRatio(const Vec3& u) const;

  Mat3 a_;            // A = S R
  Mat3 a_inv_t_;      // A^-T
  double det_a_;      // |A| = alpha_x alpha_y
  Vec3 a_n_;          // A n
  double a_n_norm_;   // |A n|
};

}  // namespace svbtdf::model
