#include "svbtdf/model/slab_transmission.h"

#include <cmath>
#include <string>

#include "svbtdf/common/error.h"
#include "svbtdf/model/dual_microfacet.h"
#include "svbtdf/model/slab_lobe.h"

namespace svbtdf::model {
namespace {

// The halo is broad and its weight is fitted: 12 x 12 polar nodes (a quarter of
// InternalReflection's default) hold its shape (docs/model.md, "Two rough interfaces").
const InternalReflectionQuadrature kQuadrature = {12, 12};

Vec2 StratumCentre(int index, int per_axis) {
  return {(index % per_axis + 0.5) / per_axis, (index / per_axis + 0.5) / per_axis};
}

// The normal on the upper hemisphere along v (a generalised half vector points either way).
Vec3 UpperNormal(const Vec3& v) { return v.z() < 0 ? Vec3(-v) : v; }

}  // namespace

SlabTransmission::SlabTransmission(const Ndf& entry, const Ndf& exit, double eta, double optical_depth,
                                   Quadrature quadrature)
    : entry_(entry), exit_(exit), eta_(eta), optical_depth_(optical_depth), per_axis_(quadrature.per_axis) {
  if (!(eta > 1.0) || !std::isfinite(eta)) {
    common::ThrowInvalidInput("eta", "the relative index of refraction must be > 1, got " + std::to_string(eta));
  }
  if (!(optical_depth >= 0.0) || !std::isfinite(optical_depth)) {
    common::ThrowInvalidInput("optical depth", "must be finite and >= 0, got " + std::to_string(optical_depth));
  }
  if (quadrature.per_axis < 2) common::ThrowInvalidInput("quadrature", "needs at least 2 points per axis");
}

double SlabTransmission::Attenuation(const Vec3& d) const {
  return optical_depth_ > 0 ? std::exp(-optical_depth_ / d.z()) : 1.0;
}

// The entry's normal h1 that refracts the light (arriving along -i) into d is the generalised half
// vector of i (index 1) and d (index eta); |d omega_h / d omega_d| = eta^2 |d.h| / |i + eta d|^2
// (Walter et al. 2007 eq. 17).
double SlabTransmission::EntryPdf(const Vec3& i, const Vec3& d) const {
  const Vec3 sum = i + eta_ * d;
  const double length2 = sum.squaredNorm();
  if (!(length2 > 0)) return 0.0;
  const Vec3 h = UpperNormal(-sum / std::sqrt(length2));
  const double cos_dh = d.dot(h);
  if (i.dot(h) >= 0 || cos_dh <= 0) return 0.0;
  return entry_.VisibleNormalPdf(-i, h) * eta_ * eta_ * cos_dh / length2;
}

// The exit's normal h2 that refracts d into o: the half vector of -d (index eta) and o (index 1).
double SlabTransmission::ExitPdf(const Vec3& o, const Vec3& d) const {
  const Vec3 difference = eta_ * d - o;
  const double length2 = difference.squaredNorm();
  if (!(length2 > 0)) return 0.0;
  const Vec3 h = UpperNormal(difference / std::sqrt(length2));
  const double cos_dh = d.dot(h);
  if (o.dot(h) <= 0 || cos_dh <= 0) return 0.0;
  return exit_.VisibleNormalPdf(o, h) * eta_ * eta_ * cos_dh / length2;
}

SlabTransmission::ForViewer SlabTransmission::Viewer(const Vec3& o) const {
  ForViewer viewer(*this, o);
  if (o.z() <= 0) return viewer;
  const int count = per_axis_ * per_axis_;
  viewer.exit_nodes_.reserve(count);
  for (int k = 0; k < count; ++k) {
    const NormalSample s = exit_.SampleVisibleNormal(o, StratumCentre(k, per_axis_));
    if (!(s.pdf > 0) || s.h.dot(o) <= 0) continue;
    const Vec3 into_slab = RefractThroughFacet(o, s.h, eta_);
    if (into_slab.isZero() || into_slab.z() >= 0) continue;  // refracted back up: masked
    const Vec3 d = -into_slab.normalized();
    const double value = WalterBtdf(exit_, -d, o, eta_, 1.0) * d.z() * Attenuation(d);
    const double pdf = ExitPdf(o, d);
    if (value > 0 && pdf > 0) viewer.exit_nodes_.push_back({d, value, pdf});
  }
  return viewer;
}

double SlabTransmission::ForViewer::Rho(const Vec3& i) const {
  const SlabTransmission& slab = slab_;
  if (i.z() >= 0 || o_.z() <= 0) return 0.0;
  const int count = slab.per_axis_ * slab.per_axis_;
  double sum = 0.0;
  // Directions the exit's normals send toward the camera, weighed by how likely the entry's
  // sampling would have found them too (the balance heuristic with equal counts).
  for (const ExitNode& node : exit_nodes_) {
    const double f_entry = WalterBtdf(slab.entry_, i, node.d, 1.0, slab.eta_);
    if (!(f_entry > 0)) continue;
    sum += f_entry * node.value / (node.pdf + slab.EntryPdf(i, node.d));
  }
  // Directions the entry's normals refract the light into.
  for (int k = 0; k < count; ++k) {
    const NormalSample s = slab.entry_.SampleVisibleNormal(-i, StratumCentre(k, slab.per_axis_));
    if (!(s.pdf > 0) || s.h.dot(-i) <= 0) continue;
    const Vec3 into_slab = RefractThroughFacet(i, -s.h, slab.eta_);
    if (into_slab.isZero() || into_slab.z() <= 0) continue;
    const Vec3 d = into_slab.normalized();
    const double f_exit = WalterBtdf(slab.exit_, -d, o_, slab.eta_, 1.0);
    if (!(f_exit > 0)) continue;
    const double f_entry = WalterBtdf(slab.entry_, i, d, 1.0, slab.eta_);
    const double pdf = slab.EntryPdf(i, d) + slab.ExitPdf(o_, d);
    if (pdf > 0) sum += f_entry * f_exit * d.z() * slab.Attenuation(d) / pdf;
  }
  return sum / count;
}

double SlabTransmission::Rho(const Vec3& i, const Vec3& o) const { return Viewer(o).Rho(i); }

SlabInternalReflection::SlabInternalReflection(const Ndf& entry, const Ndf& exit, double eta)
    : entry_(entry), exit_(exit), paths_(eta, kQuadrature) {}

double SlabInternalReflection::Rho(const Vec3& i, const Vec3& o) const {
  if (i.z() >= 0 || o.z() <= 0) return 0.0;
  return paths_.RoughEntry(entry_, i, o) + paths_.RoughExit(exit_, i, o);
}

}  // namespace svbtdf::model
