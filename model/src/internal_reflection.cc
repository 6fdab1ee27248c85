#include "svbtdf/model/internal_reflection.h"

#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <utility>

#include "svbtdf/common/error.h"
#include "svbtdf/model/dual_microfacet.h"
#include "svbtdf/model/fresnel.h"
#include "svbtdf/model/slab_lobe.h"

namespace svbtdf::model {
namespace {

using Nodes = std::vector<InternalReflection::Node>;

// Polar nodes about z, theta = (pi / 2) s^2 so that narrow NDFs get nodes near the normal too.
Nodes MakeNodes(const InternalReflection::Quadrature& q) {
  Nodes nodes;
  nodes.reserve(static_cast<size_t>(q.radial) * q.azimuthal);
  for (int a = 0; a < q.radial; ++a) {
    const double s = (a + 0.5) / q.radial, theta = 0.5 * kPi * s * s;
    const double solid_angle = std::sin(theta) * (kPi * s / q.radial) * (kTwoPi / q.azimuthal);
    for (int k = 0; k < q.azimuthal; ++k) {
      // Rings are staggered by half a step so that no azimuth is favoured.
      const double phi = kTwoPi * (k + 0.5 * (a % 2)) / q.azimuthal;
      nodes.push_back({SphericalDirection(theta, phi), solid_angle});
    }
  }
  return nodes;
}

// Node tables live for the whole process, one per quadrature (there are only a few).
const Nodes& NodesFor(const InternalReflection::Quadrature& q) {
  static std::mutex mutex;
  static std::map<std::pair<int, int>, std::unique_ptr<const Nodes>> cache;
  const std::lock_guard<std::mutex> lock(mutex);
  std::unique_ptr<const Nodes>& entry = cache[{q.radial, q.azimuthal}];
  if (!entry) entry = std::make_unique<const Nodes>(MakeNodes(q));
  return *entry;
}

// The half turn about z: how a rough exit's normals look once the slab is turned over.
Vec3 HalfTurn(const Vec3& v) { return {-v.x(), -v.y(), v.z()}; }

// IR_T for an NDF given as D(h) and G1(v, h) (docs: internal_reflection.h).
template <typename DFn, typename G1Fn>
double RoughEntryPaths(const Nodes& nodes, double eta, DFn d_of, G1Fn g1_of, const Vec3& i, const Vec3& o) {
  if (i.z() >= 0 || o.z() <= 0) return 0.0;
  const Vec3 t2 = Vec3(o.x(), o.y(), std::sqrt(std::max(0.0, eta * eta - o.x() * o.x() - o.y() * o.y()))) / eta;
  double sum = 0.0;
  for (const InternalReflection::Node& node : nodes) {
    const Vec3& h1 = node.h;
    const double cos_ih = -i.dot(h1);  // the light meets the facet from below
    if (cos_ih <= 0) continue;
    const double d1 = d_of(h1);
    if (!(d1 > 0)) continue;
    const Vec3 d = RefractThroughFacet(i, -h1, eta);  // travelling up inside the slab
    if (d.z() <= 0) continue;
    const double f_flat = FresnelDielectric(-d.z(), eta);  // from inside: 1 beyond the critical angle
    const Vec3 w(-d.x(), -d.y(), d.z());  // toward where the light reflected at the exit comes from
    const Vec3 h2 = (w + t2).normalized();
    const double cos_wh = w.dot(h2);
    if (cos_wh <= 0 || t2.dot(h2) <= 0) continue;
    const double f_r = FresnelDielectric(-cos_wh, eta) * d_of(h2) * g1_of(w, h2) * g1_of(t2, h2) /
                       (4.0 * w.z() * t2.z());
    if (!(f_r > 0)) continue;
    const double refraction = d1 * cos_ih * (1.0 - FresnelDielectric(cos_ih, eta)) * g1_of(i, h1) * g1_of(d, h1);
    sum += node.solid_angle * refraction * f_flat * f_r;
  }
  return (1.0 - FresnelDielectric(o.z(), eta)) * sum / (eta * eta * std::abs(i.z()));
}

}  // namespace

InternalReflection::InternalReflection(double eta, Quadrature quadrature) : eta_(eta) {
  if (!(eta > 1.0) || !std::isfinite(eta)) {
    common::ThrowInvalidInput("eta", "the relative index of refraction must be > 1, got " + std::to_string(eta));
  }
  if (quadrature.radial < 2 || quadrature.azimuthal < 3) {
    common::ThrowInvalidInput("quadrature", "needs at least 2 radial and 3 azimuthal nodes");
  }
  nodes_ = &NodesFor(quadrature);
}

double InternalReflection::RoughEntry(const Ndf& ndf, const Vec3& i, const Vec3& o) const {
  return RoughEntryPaths(
      *nodes_, eta_, [&](const Vec3& h) { return ndf.D(h); },
      [&](const Vec3& v, const Vec3& h) { return ndf.G1(v, h); }, i, o);
}

double InternalReflection::RoughExit(const Ndf& ndf, const Vec3& i, const Vec3& o) const {
  return RoughEntryPaths(
      *nodes_, eta_, [&](const Vec3& h) { return ndf.D(HalfTurn(h)); },
      [&](const Vec3& v, const Vec3& h) { return ndf.G1(HalfTurn(v), HalfTurn(h)); }, FlipZ(o), FlipZ(i));
}

double InternalReflection::Blend(const Ndf& ndf, double alpha, const Vec3& i, const Vec3& o) const {
  if (alpha >= 1.0) return RoughEntry(ndf, i, o);
  if (alpha <= 0.0) return RoughExit(ndf, i, o);
  return LogBlend(RoughEntry(ndf, i, o), RoughExit(ndf, i, o), alpha);
}

}  // namespace svbtdf::model
