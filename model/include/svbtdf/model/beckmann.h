#pragma once
// Anisotropic Beckmann NDF (the Gaussian slope distribution of Dai et al.'s Fig. 5) with its exact
// Smith masking and visible-normal sampling (Heitz and d'Eon 2014, with Jakob's 2014 inversion of
// the visible-slope CDF).

#include "svbtdf/model/ndf.h"

namespace svbtdf::model {

class BeckmannNdf final : public Ndf {
 public:
  // Throws svbtdf::Error(kInvalidInput) unless both alphas are finite and > 0.
  BeckmannNdf(double alpha_x, double alpha_y);
  explicit BeckmannNdf(double alpha) : BeckmannNdf(alpha, alpha) {}

  double alpha_x() const { return alpha_x_; }
  double alpha_y() const { return alpha_y_; }

  std::string name() const override { return "beckmann"; }
  // D(h) = exp(-(hx^2/ax^2 + hy^2/ay^2) / hz^2) / (pi ax ay hz^4) for h.z > 0.
  double D(const Vec3& h) const override;
  // G1 = chi+(v'.h) / (1 + Lambda(v')), Lambda = (erf(a) - 1)/2 + exp(-a^2) / (2 a sqrt(pi)),
  // a = vz / sqrt(ax^2 vx^2 + ay^2 vy^2).
  double G1(const Vec3& v, const Vec3& h) const override;
  double Lambda(const Vec3& v) const;
  // Samples the visible slopes of the unit-roughness distribution for the stretched direction,
  // rotates and unstretches them. The slope CDF is inverted to 1e-12, so the weight is 1.
  NormalSample SampleVisibleNormal(const Vec3& v, const Vec2& u) const override;
  double VisibleNormalPdf(const Vec3& v, const Vec3& h) const override;
  std::unique_ptr<Ndf> Clone() const override { return std::make_unique<BeckmannNdf>(*this); }

 private:
  double alpha_x_;
  double alpha_y_;
};

// Inverse of the error function on (-1, 1), accurate to about 1e-15 (Giles 2010 initial guess
// refined by Newton steps on std::erf).
double ErfInv(double y);

}  // namespace svbtdf::model
