#pragma once
// The physically parameterised fit (`svbtdf fit --model slab`): every texel as a slab with two
// rough interfaces, an anisotropic GGX of its own on each side, R = k_s rho + rho_d with rho the
// light the two interfaces transmit without reflecting inside (model/slab_transmission.h) plus a
// fitted weight of the light reflected inside. A lab learns how rough each side is ("entry 0.30,
// exit 0.12", or "entry 0.08 x 0.35 along y") instead of an NDF table and a blend weight. Fitted
// with Ceres on the residuals of rho itself (not of its logarithm, as the dual-microfacet fit and
// the baseline do; slab_fit.cc says why), the linear amounts in closed form (docs/fitting.md,
// "The slab fit").

#include <array>
#include <optional>

#include "svbtdf/fit/texel_fit.h"
#include "svbtdf/model/ellipsoid_ndf.h"
#include "svbtdf/model/ggx.h"
#include "svbtdf/model/vec.h"

namespace svbtdf::fit {

// One interface: GGX with alpha_x along the axis at `azimuth` (radians from +x toward +y, in
// (-pi/2, pi/2]) and alpha_y across it, alpha_x >= alpha_y; isotropic when they are equal. GGX
// alphas, not perceptual roughness.
struct SlabSide {
  double alpha_x = 0.2, alpha_y = 0.2;
  double azimuth = 0.0;

  static SlabSide Isotropic(double roughness) { return {roughness, roughness, 0.0}; }
  // The same side with both alphas times `factor`.
  SlabSide Widened(double factor) const { return {alpha_x * factor, alpha_y * factor, azimuth}; }
  // sqrt(alpha_x alpha_y): the isotropic roughness whose slopes spread over the same area.
  double Roughness() const;
};

// The two interfaces of a texel.
struct SlabInterfaces {
  SlabSide entry = {};  // the side facing the light (the monitor)
  SlabSide exit = {};   // the side facing the camera
  // Weight of the light reflected inside the slab (model::SlabInternalReflection's shape) against
  // the light transmitted straight through; 0: none.
  double internal_reflection = 0.0;
  // Weight of the longer internal paths' shape (the same with both sides widened by
  // model::kLongerPathsWidening); 0: none.
  double longer_paths = 0.0;
};

// The NDF of one side, built in whichever of the two slots it needs (an axis-aligned GGX, or the
// Ellipsoid NDF that is GGX turned about z) and returned; valid while the slot is.
const model::Ndf& SideNdf(const SlabSide& side, std::optional<model::GgxNdf>* ggx, std::optional<model::EllipsoidNdf>* turned);

// The NDFs of a texel's two sides (SideNdf), each side's alphas times `widening` (1: as fitted;
// model::kLongerPathsWidening: the longer internal paths' shape). Not copyable: the NDFs are
// referenced by whatever evaluates them.
class SlabNdfs {
 public:
  explicit SlabNdfs(const SlabInterfaces& slab, double widening = 1.0)
      : entry_(&SideNdf(slab.entry.Widened(widening), &entry_ggx_, &entry_turned_)),
        exit_(&SideNdf(slab.exit.Widened(widening), &exit_ggx_, &exit_turned_)) {}
  SlabNdfs(const SlabNdfs&) = delete;
  SlabNdfs& operator=(const SlabNdfs&) = delete;
  const model::Ndf& entry() const { return *entry_; }
  const model::Ndf& exit() const { return *exit_; }

 private:
  std::optional<model::GgxNdf> entry_ggx_, exit_ggx_;
  std::optional<model::EllipsoidNdf> entry_turned_, exit_turned_;
  const model::Ndf* entry_;
  const model::Ndf* exit_;
};

// rho(i, o) of the slab with unit scale: SlabTransmission(entry, exit, eta) with the default
// quadrature, plus internal_reflection x SlabInternalReflection of the same interfaces and
// longer_paths x the same of the widened interfaces. The one evaluation of the slab model: the
// fitter and fitted materials (MaterialEvaluator) share it.
double SlabShape(const SlabInterfaces& slab, double eta, const model::Vec3& i, const model::Vec3& o);

struct SlabFitResult {
  SlabInterfaces interfaces;
  // Standard errors of each side's Roughness() from the fit's Jacobian (the sandwich estimate,
  // slab_fit.cc; -1 where it could not be computed). A roughness whose standard error is large
  // against its value is one the dots do not constrain.
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
  // Fit each side's anisotropy (alpha_x, alpha_y, azimuth) after the isotropic fit; false keeps
  // both sides isotropic. Off by default: it fits anisotropic samples far better, but on
  // isotropic ones it finds anisotropy in the model's own errors (docs/validation.md, "The slab
  // fit"), and it takes several times as long.
  bool anisotropic = false;
  // The anisotropic fit is kept only when its relative RMSE is at most this fraction of the
  // isotropic fit's (slab_fit.cc says why).
  double anisotropy_gain = 0.9;
  // Fit the weight of the light reflected inside the slab too (SlabInterfaces::internal_reflection).
  bool internal_reflection = true;
  // ... and of the longer internal paths' shape beside it (SlabInterfaces::longer_paths).
  bool longer_paths = true;
  // Its shape depends on the interfaces: it is computed at the last fit's and the fit repeated,
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
