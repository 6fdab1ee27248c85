#include "svbtdf/model/slab_lobe.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "svbtdf/common/error.h"
#include "svbtdf/model/fresnel.h"

namespace svbtdf::model {
namespace {

// Smith G1 of a Beckmann microsurface of roughness a for a direction of polar cosine c, at the
// mean normal (Walter et al. 2007 eq. 27 with the exact Lambda).
double BeckmannG1(double a, double c) {
  c = std::abs(c);
  if (c >= 1.0) return 1.0;
  if (c <= 0.0) return 0.0;
  const double tan_theta = std::sqrt(1.0 - c * c) / c;
  const double x = 1.0 / (a * tan_theta);
  const double lambda = 0.5 * (std::erf(x) - 1.0) + std::exp(-x * x) / (2.0 * x * std::sqrt(kPi));
  return 1.0 / (1.0 + lambda);
}

// The Smith masking of one rough interface for the mean path, which meets it along the air-side
// cosine and the in-slab cosine; 1 for a flat interface.
double MeanPathMasking(double kappa, double cos_air, double cos_slab) {
  if (!std::isfinite(kappa)) return 1.0;
  const double a = std::sqrt(2.0 / kappa);
  return BeckmannG1(a, cos_air) * BeckmannG1(a, cos_slab);
}

}  // namespace

double VmfMeanCosine(double kappa) {
  if (!std::isfinite(kappa)) return 1.0;
  if (kappa < 1e-4) return kappa / 3.0;
  const double e = std::exp(-2.0 * kappa);
  return (1.0 + e) / (1.0 - e) - 1.0 / kappa;  // coth(kappa) - 1 / kappa
}

double VmfConcentrationForMeanCosine(double mean_cosine) {
  if (mean_cosine >= 1.0) return kFlatConcentration;
  if (!(mean_cosine > 0.0)) common::ThrowInvalidInput("mean cosine", "must lie in (0, 1]");
  // Banerjee et al. 2005's approximation for the sphere, then Newton on A3, whose derivative is
  // 1 / kappa^2 - 1 / sinh^2 kappa (written with exp(-2 kappa) to stay finite).
  const double m = mean_cosine;
  double kappa = m * (3.0 - m * m) / (1.0 - m * m);
  for (int k = 0; k < 8; ++k) {
    const double e = std::exp(-2.0 * kappa);
    const double slope = 1.0 / (kappa * kappa) - 4.0 * e / Square(1.0 - e);
    if (!(slope > 0)) break;
    const double step = (VmfMeanCosine(kappa) - m) / slope;
    kappa = std::max(0.5 * kappa, kappa - step);
    if (std::abs(step) < 1e-12 * kappa) break;
  }
  return kappa;
}

double VmfDensity(double kappa, double cosine) {
  if (kappa < 1e-8) return 1.0 / (4.0 * kPi);
  return kappa / (kTwoPi * -std::expm1(-2.0 * kappa)) * std::exp(kappa * (cosine - 1.0));
}

double MatchedVmfConcentration(const Ndf& ndf) {
  // Polar nodes theta = (pi / 2) s^2, dense near the normal where sharp NDFs live.
  constexpr int kRadial = 600, kAzimuth = 64;
  double mass = 0.0, moment = 0.0;
  for (int a = 0; a < kRadial; ++a) {
    const double s = (a + 0.5) / kRadial, theta = 0.5 * kPi * s * s;
    const double d_theta = kPi * s / kRadial;
    for (int k = 0; k < kAzimuth; ++k) {
      const Vec3 h = SphericalDirection(theta, kTwoPi * (k + 0.5) / kAzimuth);
      const double w = ndf.D(h) * h.z() * std::sin(theta) * d_theta * kTwoPi / kAzimuth;
      mass += w;
      moment += w * h.z();
    }
  }
  if (!(mass > 0)) common::ThrowInvalidInput("ndf", "has no mass on the upper hemisphere");
  return VmfConcentrationForMeanCosine(std::min(1.0, moment / mass));
}

Vec3 RefractThroughFacet(const Vec3& from, const Vec3& m, double eta) {
  const double cos_i = from.dot(m);
  const double sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
  if (sin2_t >= 1.0) return Vec3::Zero();
  return -from / eta + (cos_i / eta - std::sqrt(1.0 - sin2_t)) * m;
}

double FacetToRefractedJacobian(const Vec3& from, const Vec3& m, double eta) {
  const Vec3 t = RefractThroughFacet(from, m, eta);
  if (t.isZero()) return 0.0;
  return eta * eta * std::abs(t.dot(m)) / Square(from.dot(m) + eta * t.dot(m));
}

double FlatRefractionJacobian(double cos_from, double eta) {
  const double sin2_to = (1.0 - cos_from * cos_from) / (eta * eta);
  if (sin2_to >= 1.0 || !(cos_from > 0)) return 0.0;
  return eta * eta * std::sqrt(1.0 - sin2_to) / cos_from;
}

SlabLobeModel::SlabLobeModel(const SlabLobeParams& params) : params_(params) {
  if (!(params.eta > 1.0) || !std::isfinite(params.eta)) {
    common::ThrowInvalidInput("eta", "the relative index of refraction must be > 1, got " + std::to_string(params.eta));
  }
  if (!(params.kappa_entry > 0) || !(params.kappa_exit > 0)) {
    common::ThrowInvalidInput("kappa", "both interfaces' vMF concentrations must be > 0 (infinite: flat)");
  }
}

// Traced from the viewer: o refracts through the exit's mean normal z into t (t.z < 0), which
// leaves through the entry's mean normal into i = -o. From inside the slab the entry's normal
// facing t's side is again z, and the incident direction on that side is -t.
SlabLobeModel::Jacobians SlabLobeModel::MeanPathJacobians(const Vec3& o) const {
  const double eta = params_.eta;
  const Vec3 z = Vec3::UnitZ();
  const Vec3 t = RefractThroughFacet(o, z, eta);
  Jacobians j;
  j.exit_to_slab = FacetToRefractedJacobian(o, z, eta);
  // |d omega_t / d omega_i| for the flat map from the slab (index eta) into air (relative 1/eta).
  j.slab_to_light = FlatRefractionJacobian(-t.z(), 1.0 / eta);
  j.exit_to_light = j.exit_to_slab * j.slab_to_light;
  j.entry_to_light = FacetToRefractedJacobian(-t, z, 1.0 / eta);
  return j;
}

double SlabLobeModel::LightConcentration(const Vec3& o) const {
  const Jacobians j = MeanPathJacobians(o);
  const double mean_cosine = VmfMeanCosine(j.exit_to_light * params_.kappa_exit) *
                             VmfMeanCosine(j.entry_to_light * params_.kappa_entry);
  return VmfConcentrationForMeanCosine(mean_cosine);
}

double SlabLobeModel::Energy(const Vec3& o) const {
  if (o.z() <= 0) return 0.0;
  const double eta = params_.eta;
  const double cos_t = std::sqrt(std::max(0.0, 1.0 - (1.0 - o.z() * o.z()) / (eta * eta)));
  const double transmit = 1.0 - FresnelDielectric(o.z(), eta);
  return transmit * transmit * MeanPathMasking(params_.kappa_exit, o.z(), cos_t) *
         MeanPathMasking(params_.kappa_entry, o.z(), cos_t);
}

double SlabLobeModel::Rho(const Vec3& i, const Vec3& o) const {
  if (i.z() >= 0 || o.z() <= 0) return 0.0;
  const double kappa = LightConcentration(o);
  if (!std::isfinite(kappa)) return 0.0;
  return Energy(o) * VmfDensity(kappa, -i.dot(o)) / std::abs(i.z());
}

}  // namespace svbtdf::model
