#pragma once
// The baseline the paper compares against (its "GGX", Walter et al. 2007): a single rough
// refraction from air into the slab, f = k WalterBtdf(GGX(alpha_x, alpha_y, azimuth), i, o, 1, eta)
// with the camera direction taken as the refracted one, fitted per texel with Ceres on the same
// log residuals as the dual-microfacet fit (`svbtdf fit --model ggx`).

#include "svbtdf/fit/texel_fit.h"

namespace svbtdf::fit {

struct BaselineFitResult {
  double alpha_x = 0.2, alpha_y = 0.2;
  double azimuth = 0.0;  // rotation of the anisotropy axes about z, radians
  double k_s = 1.0;
  double log_rms = 0.0;
  double relative_rmse = 0.0;
  bool converged = false;
};

class BaselineFitter {
 public:
  explicit BaselineFitter(double eta, double dark_fraction = 2e-3);
  BaselineFitResult Fit(const TexelSlice& slice) const;
  double Rho(const BaselineFitResult& fit, const Vec3& i, const Vec3& o) const;

 private:
  double eta_;
  double dark_fraction_;
};

}  // namespace svbtdf::fit
