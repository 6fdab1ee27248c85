#pragma once
// The baseline the paper compares against (its "GGX", Walter et al. 2007): a single rough
// refraction from air into the slab, f = k WalterBtdf(GGX(alpha_x, alpha_y, azimuth), i, o, 1, eta)
// with the camera direction taken as the refracted one, fitted per texel with Ceres on the same
// log residuals as the dual-microfacet fit (`svbtdf fit --model ggx`).

#include <array>
#include <utility>
#include <vector>

#include "svbtdf/fit/texel_fit.h"
#include "svbtdf/model/hemicube.h"

namespace svbtdf::fit {

// The baseline's anisotropic GGX lobe.
struct BaselineLobe {
  double alpha_x = 0.2, alpha_y = 0.2;
  double azimuth = 0.0;  // rotation of the anisotropy axes about z, radians
};

// The baseline BTDF with unit scale: WalterBtdf(GGX(alpha_x, alpha_y) rotated by azimuth, i, o, 1, eta).
// The one evaluation of the baseline: the fitter and fitted materials (MaterialEvaluator) share it.
double BaselineShape(const BaselineLobe& lobe, double eta, const model::Vec3& i, const model::Vec3& o);

// ln D of the rotated GGX at every cell centre of `grid` (a material stores it as the texel's NDF).
std::vector<double> BaselineLnD(const model::Hemicube& grid, const BaselineLobe& lobe);

// The weighted mean of lobes (affine weights, sum 1). Azimuths cannot be averaged directly (they
// wrap at pi and mean nothing for an isotropic lobe), so the GGX slope second-moment matrices
// R diag(alpha_x^2, alpha_y^2) R^T are averaged and decomposed again.
BaselineLobe BlendBaselineLobes(const std::vector<std::pair<BaselineLobe, double>>& weighted);

struct BaselineFitResult {
  double alpha_x = 0.2, alpha_y = 0.2;
  double azimuth = 0.0;  // rotation of the anisotropy axes about z, radians
  double k_s = 1.0;
  std::array<double, 3> k_s_rgb = {1.0, 1.0, 1.0};  // per channel, when the slice has rho_rgb
  double log_rms = 0.0;
  double relative_rmse = 0.0;
  bool converged = false;

  BaselineLobe lobe() const { return {alpha_x, alpha_y, azimuth}; }
};

class BaselineFitter {
 public:
  explicit BaselineFitter(double eta, double dark_fraction = 2e-3);
  BaselineFitResult Fit(const TexelSlice& slice) const;
  double Rho(const BaselineFitResult& fit, const model::Vec3& i, const model::Vec3& o) const;

 private:
  double eta_;
  double dark_fraction_;
};

}  // namespace svbtdf::fit
