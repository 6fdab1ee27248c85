#pragma once
// The physically parameterised fit (`svbtdf fit --model slab`): every texel as a slab with two
// rough interfaces, isotropic GGX of its own roughness on each side, R = k_s rho + rho_d with rho
// the light the two interfaces transmit without reflecting inside (model/slab_transmission.h).
// A lab learns the two sides' roughnesses ("entry 0.30, exit 0.12") instead of an NDF table and
// a blend weight. Fitted with Ceres on the residuals of rho itself (not of its logarithm, as the
// dual-microfacet fit and the baseline do; slab_fit.cc says why), k_s in closed form
// (docs/fitting.md, "The slab fit").

#include <array>

#include "svbtdf/fit/texel_fit.h"
#include "svbtdf/model/vec.h"

namespace svbtdf::fit {

// The two interfaces of a texel: GGX alphas (not perceptual roughness).
struct SlabInterfaces {
  double entry_roughness = 0.2;  // the side facing the light (the monitor)
  double exit_roughness = 0.2;   // the side facing the camera
  // Weight of the light reflected inside the slab (model::SlabInternalReflection's shape) against
  // the light transmitted straight through; 0: none.
  double internal_reflection = 0.0;
};

// rho(i, o) of the slab with unit scale: SlabTransmission(GGX(entry), GGX(exit), eta) with the
// default quadrature, plus internal_reflection x SlabInternalReflection of the same interfaces.
// The one evaluation of the slab model: the fitter and fitted materials (MaterialEvaluator)
// share it.
double SlabShape(const SlabInterfaces& slab, double eta, const model::Vec3& i, const model::Vec3& o);

struct SlabFitResult {
  SlabInterfaces interfaces;
  // Standard errors of the two roughnesses from the fit's normal equations (the inverse of
  // J^T J scaled by the residuals' variance; -1 where it could not be computed). A roughness whose
  // standard error is large against its value is one the dots do not constrain.
  double entry_roughness_se = -1.0, exit_roughness_se = -1.0;
  // Their correlation: near -1 where the data fix only a combination of the two (the lobe's
  // width), not how it is shared between the sides.
  double roughness_correlation = 0.0;
  double k_s = 1.0;
  std::array<double, 3> k_s_rgb = {1.0, 1.0, 1.0};  // per channel, when the slice has rho_rgb
  double log_rms = 0.0;        // RMS of ln(fitted / measured) over the bright samples (for comparison)
  double relative_rmse = 0.0;  // RMS of fitted - measured over that of measured: what the fit minimises
  bool converged = false;
};

struct SlabFitOptions {
  // Fit the weight of the light reflected inside the slab too (SlabInterfaces::internal_reflection).
  bool internal_reflection = true;
  // Its shape depends on the roughnesses: it is computed at the last fit's and the fit repeated,
  // this many times (a fixed-point iteration).
  int internal_reflection_passes = 2;
  double dark_fraction = 2e-3;  // samples below this fraction of the brightest do not count as a lobe
};

class SlabFitter {
 public:
  // Throws svbtdf::common::Error(kInvalidInput) unless eta is finite and > 1.
  explicit SlabFitter(double eta, SlabFitOptions options = {});
  // Throws svbtdf::common::Error(kNumerical) for a slice with too few bright samples.
  SlabFitResult Fit(const TexelSlice& slice) const;
  double Rho(const SlabFitResult& fit, const model::Vec3& i, const model::Vec3& o) const;

 private:
  double eta_;
  SlabFitOptions options_;
};

}  // namespace svbtdf::fit
