#pragma once
// The von Mises-Fisher NDF (Guo, Qian and Pan 2015): D(h) proportional to exp(kappa mu.h) on the
// upper hemisphere, with a possibly tilted mean normal mu and concentration kappa, normalised by
// the projected-area condition. Its Smith masking is derived from its own projected area.

#include <vector>

#include "svbtdf/model/ndf.h"

namespace svbtdf::model {

class VmfNdf final : public Ndf {
 public:
  // Throws svbtdf::Error(kInvalidInput) unless kappa is in (0, 1e5] and mean has z > 0.
  VmfNdf(const Vec3& mean, double kappa);

  std::string name() const override { return "vmf"; }
  // D(h) = exp(kappa (mu.h - 1) - ln_norm_) for h.z > 0.
  double D(const Vec3& h) const override;
  // G1 = chi+(v.h) min(1, v.z / A(v)), A(v) = integral of max(0, v.h) D(h), tabulated.
  double G1(const Vec3& v, const Vec3& h) const override;
  // Exact: vMF lobe samples (Jakob 2012's stable inversion) accepted with probability
  // max(0, v.h) when h.z > 0. pdf = max(0, v.h) D(h) / A(v); weight = min(1, A(v) / v.z) <= 1.
  NormalSample SampleVisibleNormal(const Vec3& v, const Vec2& u) const override;
  double VisibleNormalPdf(const Vec3& v, const Vec3& h) const override;
  std::unique_ptr<Ndf> Clone() const override { return std::make_unique<VmfNdf>(*this); }

  double ProjectedArea(const Vec3& v) const;

 private:
  Vec3 SampleLobe(double u1, double u2) const;

  Vec3 mean_;
  double kappa_;
  double ln_norm_;  // ln of the integral of exp(kappa (mu.h - 1)) h.z over the upper hemisphere
  std::vector<double> area_;  // A(v) on a (theta, phi) grid
};

}  // namespace svbtdf::model
