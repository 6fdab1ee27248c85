#pragma once
// Anisotropic GGX / Trowbridge-Reitz NDF (Walter et al. 2007; Heitz 2014) with its exact Smith
// masking and exact visible-normal sampling. alpha_x and alpha_y are the GGX alphas along the
// sample frame's x and y axes (not perceptual roughness); equal values give isotropic GGX.

#include "svbtdf/model/ndf.h"

namespace svbtdf::model {

class GgxNdf final : public Ndf {
 public:
  // Throws svbtdf::Error(kInvalidInput) unless both alphas are finite and > 0.
  GgxNdf(double alpha_x, double alpha_y);
  explicit GgxNdf(double alpha) : GgxNdf(alpha, alpha) {}

  double alpha_x() const { return alpha_x_; }
  double alpha_y() const { return alpha_y_; }

  std::string name() const override { return "ggx"; }
  // D(h) = 1 / (pi ax ay (hx^2/ax^2 + hy^2/ay^2 + hz^2)^2) for h.z > 0.
  double D(const Vec3& h) const override;
  // G1 = chi+(v'.h) / (1 + Lambda(v')), Lambda = (sqrt(1 + (ax^2 vx^2 + ay^2 vy^2)/vz^2) - 1) / 2.
  double G1(const Vec3& v, const Vec3& h) const override;
  double Lambda(const Vec3& v) const;
  // Exact sampling of D_v(h) = G1(v,h) max(0, v.h) D(h) / v.z: stretch v to the unit-roughness
  // configuration, sample the visible hemisphere as a spherical cap (Dupuy and Benyoub 2023, an
  // equivalent simplification of Heitz 2018), unstretch. The weight is exactly 1.
  NormalSample SampleVisibleNormal(const Vec3& v, const Vec2& u) const override;
  double VisibleNormalPdf(const Vec3& v, const Vec3& h) const override;
  std::unique_ptr<Ndf> Clone() const override { return std::make_unique<GgxNdf>(*this); }

 private:
  double alpha_x_;
  double alpha_y_;
};

}  // namespace svbtdf::model
