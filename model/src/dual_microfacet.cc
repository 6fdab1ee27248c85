#include "svbtdf/model/dual_microfacet.h"

#include <cmath>
#include <string>

#include "svbtdf/common/error.h"
#include "svbtdf/model/fresnel.h"
#include "svbtdf/model/internal_reflection.h"
#include "svbtdf/model/polarisation.h"

namespace svbtdf::model {
namespace {

// eta times the in-slab direction whose tangential component is `tangential` (Snell at a flat
// interface: the tangential component of eta * direction is continuous).
Vec3 ScaledSlabDirection(double tx, double ty, double eta) {
  return {tx, ty, std::sqrt(std::max(0.0, eta * eta - tx * tx - ty * ty))};
}

// The geometry of each configuration, shared by its evaluation and by HalfVectors.
struct EntryGeometry {
  Vec3 om;  // eta times the in-slab direction toward the flat exit
  Vec3 h;
  double length2 = 0, cos_ih = 0, cos_omh = 0;
};

std::optional<EntryGeometry> RoughEntryGeometry(const Vec3& i, const Vec3& o, double eta) {
  if (i.z() >= 0 || o.z() <= 0) return std::nullopt;
  EntryGeometry g;
  g.om = ScaledSlabDirection(o.x(), o.y(), eta);
  const Vec3 sum = i + g.om;
  g.length2 = sum.squaredNorm();
  if (sum.z() <= 0 || g.length2 <= 0) return std::nullopt;
  g.h = sum / std::sqrt(g.length2);
  g.cos_ih = i.dot(g.h);
  g.cos_omh = g.om.dot(g.h);
  // Refraction through a facet needs the light below it and the refracted ray above it.
  if (g.cos_ih >= 0 || g.cos_omh <= 0) return std::nullopt;
  return g;
}

struct ExitGeometry {
  Vec3 im;  // eta times the in-slab direction from the flat entry
  Vec3 h;
  double length2 = 0, cos_imh = 0, cos_oh = 0;
};

std::optional<ExitGeometry> RoughExitGeometry(const Vec3& i, const Vec3& o, double eta) {
  if (i.z() >= 0 || o.z() <= 0) return std::nullopt;
  ExitGeometry g;
  g.im = ScaledSlabDirection(-i.x(), -i.y(), eta);
  const Vec3 difference = g.im - o;
  g.length2 = difference.squaredNorm();
  if (difference.z() <= 0 || g.length2 <= 0) return std::nullopt;
  g.h = difference / std::sqrt(g.length2);
  g.cos_imh = g.im.dot(g.h);
  g.cos_oh = o.dot(g.h);
  if (g.cos_imh <= 0 || g.cos_oh <= 0) return std::nullopt;
  return g;
}

}  // namespace

DualMicrofacetModel::DualMicrofacetModel(double eta, SmithShadowing shadowing)
    : eta_(eta), shadowing_(shadowing) {
  if (!(eta > 1.0) || !std::isfinite(eta)) {
    common::ThrowInvalidInput("eta", "the relative index of refraction must be > 1, got " + std::to_string(eta),
                      "eta = n_slab / n_air, e.g. 1.5 for glass");
  }
}

VirtualConfiguration DualMicrofacetModel::RoughEntry(const Vec3& i, const Vec3& o, const Vec3* field) const {
  VirtualConfiguration config;
  const std::optional<EntryGeometry> g = RoughEntryGeometry(i, o, eta_);
  if (!g) return config;
  // Through the facet h into the slab, then out through the flat exit (normal z).
  const double transmit = field ? TwoInterfaceTransmittance(-i, *field, g->h, eta_, Vec3::UnitZ(), 1.0 / eta_)
                                : (1.0 - FresnelDielectric(-g->cos_ih, eta_)) * (1.0 - FresnelDielectric(o.z(), eta_));
  const double shadowing = shadowing_.G(i, g->om / eta_, g->h);
  config.valid = true;
  config.h = g->h;
  config.factor = transmit * shadowing * std::abs(g->cos_ih) * g->cos_omh /
                  (std::abs(i.z()) * g->om.z() * g->length2);
  return config;
}

VirtualConfiguration DualMicrofacetModel::RoughExit(const Vec3& i, const Vec3& o, const Vec3* field) const {
  VirtualConfiguration config;
  const std::optional<ExitGeometry> g = RoughExitGeometry(i, o, eta_);
  if (!g) return config;
  // Into the slab through the flat entry (normal z), then out through the facet h.
  const double transmit = field ? TwoInterfaceTransmittance(-i, *field, Vec3::UnitZ(), eta_, g->h, 1.0 / eta_)
                                : (1.0 - FresnelDielectric(-i.z(), eta_)) * (1.0 - FresnelDielectric(g->cos_oh, eta_));
  const double shadowing = shadowing_.G(-g->im / eta_, o, g->h);
  config.valid = true;
  config.h = g->h;
  config.factor = transmit * shadowing * g->cos_imh * g->cos_oh / (g->im.z() * o.z() * g->length2);
  return config;
}

std::array<std::optional<Vec3>, 2> DualMicrofacetModel::HalfVectors(const Vec3& i, const Vec3& o) const {
  std::array<std::optional<Vec3>, 2> h;
  if (const auto entry = RoughEntryGeometry(i, o, eta_)) h[0] = entry->h;
  if (const auto exit = RoughExitGeometry(i, o, eta_)) h[1] = exit->h;
  return h;
}

double DualMicrofacetModel::RhoT(const Ndf& ndf, const Vec3& i, const Vec3& o, const Vec3* field) const {
  const VirtualConfiguration c = RoughEntry(i, o, field);
  return c.valid ? c.factor * ndf.D(c.h) : 0.0;
}

double DualMicrofacetModel::RhoB(const Ndf& ndf, const Vec3& i, const Vec3& o, const Vec3* field) const {
  const VirtualConfiguration c = RoughExit(i, o, field);
  return c.valid ? c.factor * ndf.D(c.h) : 0.0;
}

double DualMicrofacetModel::Rho(const Ndf& ndf, double alpha, const Vec3& i, const Vec3& o, const Vec3* field) const {
  if (alpha >= 1.0) return RhoT(ndf, i, o, field);
  if (alpha <= 0.0) return RhoB(ndf, i, o, field);
  return LogBlend(RhoT(ndf, i, o, field), RhoB(ndf, i, o, field), alpha);
}

double LogBlend(double rho_T, double rho_B, double alpha) {
  if (alpha >= 1.0) return rho_T;
  if (alpha <= 0.0) return rho_B;
  if (rho_T <= 0.0 || rho_B <= 0.0) return 0.0;
  return std::exp(alpha * std::log(rho_T) + (1.0 - alpha) * std::log(rho_B));
}

double WalterBtdf(const Ndf& ndf, const Vec3& i, const Vec3& o, double eta_i, double eta_o) {
  if (i.z() * o.z() >= 0) return 0.0;
  Vec3 h = -(eta_i * i + eta_o * o);
  const double length2 = h.squaredNorm();
  if (length2 <= 0) return 0.0;
  h /= std::sqrt(length2);
  if (h.z() < 0) h = -h;
  const double cos_ih = i.dot(h);
  const double cos_oh = o.dot(h);
  if (cos_ih * cos_oh >= 0) return 0.0;
  const double g = ndf.G1(i, h) * ndf.G1(o, h);
  if (g <= 0) return 0.0;
  // The Fresnel term is evaluated on the light's side; sign tells which medium that is.
  const double transmit = 1.0 - FresnelDielectric(std::abs(cos_ih), eta_o / eta_i);
  const double denom = eta_i * cos_ih + eta_o * cos_oh;
  return std::abs(cos_ih * cos_oh / (i.z() * o.z())) * eta_o * eta_o * transmit * g * ndf.D(h) /
         (denom * denom);
}

double SpecularRho(const Ndf& ndf, const DualMicrofacetParams& params, const Vec3& i, const Vec3& o) {
  double rho = DualMicrofacetModel(params.eta, params.shadowing).Rho(ndf, params.alpha, i, o);
  if (params.internal_reflection) rho += InternalReflection(params.eta).Blend(ndf, params.alpha, i, o);
  return rho;
}

Rgb EvaluateMaterial(const Ndf& ndf, const DualMicrofacetParams& params, const Vec3& i,
                     const Vec3& o) {
  const double rho = SpecularRho(ndf, params, i, o);
  return {params.k_s[0] * rho + params.rho_d[0], params.k_s[1] * rho + params.rho_d[1],
          params.k_s[2] * rho + params.rho_d[2]};
}

}  // namespace svbtdf::model
