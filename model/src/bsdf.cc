#include "svbtdf/model/bsdf.h"

#include <algorithm>
#include <cmath>

#include "svbtdf/common/error.h"
#include "svbtdf/model/internal_reflection.h"

namespace svbtdf::model {
namespace {

// Below this o.z (about 0.6 degrees above the horizon) the rough-exit strategy is not used, in
// Sample and Pdf alike: visible-normal samplers that work by rejection (the tabulated NDF) slow
// down without bound there, and the other two strategies still cover every direction.
constexpr double kMinRoughExitCosine = 1e-2;

// The least share of Sample's draws the cosine gets when a texel has the internal-reflection term.
constexpr double kInternalReflectionCosineShare = 0.2;

bool OppositeSides(const Vec3& wi, const Vec3& wo) { return wi.z() * wo.z() < 0; }

double CosineTransmissionPdf(const Vec3& wi, const Vec3& wo) {
  return OppositeSides(wi, wo) ? std::abs(wi.z()) * kInvPi : 0.0;
}

// The share of samples Sample gives the cosine: the diffuse part's energy (pi rho_d) against the
// specular part's (at most k_s), never below 5% so that the specular samplers are never the only
// ones covering a direction whose log-blended lobe they both fit poorly.
double DiffuseProbability(const Rgb& k_s, const Rgb& rho_d) {
  const double specular = std::max(0.0, Luminance(k_s));
  const double diffuse = std::max(0.0, kPi * Luminance(rho_d));
  if (!(specular + diffuse > 0)) return 1.0;
  return std::clamp(diffuse / (specular + diffuse), 0.05, 1.0);
}

Rgb Scaled(const Rgb& rgb, double s) { return {rgb[0] * s, rgb[1] * s, rgb[2] * s}; }

// The direction that leaves a facet with normal h (h.d > 0) into a medium of relative index
// 1 / ratio, for d pointing away from the facet in the medium it comes from (ratio = n_from /
// n_to); nullopt on total internal reflection.
std::optional<Vec3> Refract(const Vec3& d, const Vec3& h, double ratio) {
  const double cos_d = d.dot(h);
  const double sin2_t = ratio * ratio * (1.0 - cos_d * cos_d);
  if (sin2_t >= 1.0) return std::nullopt;
  return Vec3(-ratio * d + (ratio * cos_d - std::sqrt(1.0 - sin2_t)) * h);
}

std::optional<BsdfSample> Finish(const Bsdf& bsdf, const Vec3& wi, const Vec3& wo) {
  const double pdf = bsdf.Pdf(wi, wo);
  if (!(pdf > 0)) return std::nullopt;
  return BsdfSample{wi, pdf, Scaled(bsdf.Eval(wi, wo), std::abs(wi.z()) / pdf)};
}

}  // namespace

Vec3 SampleCosineTransmission(const Vec3& wo, const Vec2& u) {
  const double r = std::sqrt(u.x()), phi = kTwoPi * u.y();
  const double z = std::sqrt(std::max(0.0, 1.0 - u.x()));
  return {r * std::cos(phi), r * std::sin(phi), wo.z() > 0 ? -z : z};
}

// The one-rough-side configurations' samplers, drawing from the visible normals of `proposal`:
// DualMicrofacetBsdf's two strategies, and SlabBsdf's (one per interface).
namespace {

// Rough entry: om = eta t is fixed by o, and h_T = normalize(i + om) is a visible normal of the
// in-slab direction t refracted out into the air; dw_h / dw_i = |i.h| / |i + om|^2 (Walter eq. 17
// with the light's side in air).
std::optional<Vec3> SampleRoughEntry(const Ndf& proposal, double eta, const Vec3& o, const Vec2& u) {
  const Vec3 om(o.x(), o.y(), std::sqrt(std::max(0.0, eta * eta - o.x() * o.x() - o.y() * o.y())));
  const Vec3 t = om / eta;
  const NormalSample s = proposal.SampleVisibleNormal(t, u);
  if (!(s.pdf > 0) || s.h.dot(t) <= 0) return std::nullopt;
  const std::optional<Vec3> i = Refract(t, s.h, eta);
  if (!i || i->z() >= 0) return std::nullopt;
  return i->normalized();
}

double RoughEntryPdf(const Ndf& proposal, double eta, const Vec3& i, const Vec3& o) {
  const Vec3 om(o.x(), o.y(), std::sqrt(std::max(0.0, eta * eta - o.x() * o.x() - o.y() * o.y())));
  const Vec3 sum = i + om;
  const double length2 = sum.squaredNorm();
  if (!(length2 > 0)) return 0.0;
  const Vec3 h = sum / std::sqrt(length2);
  if (h.z() <= 0 || i.dot(h) >= 0 || om.dot(h) <= 0) return 0.0;
  return proposal.VisibleNormalPdf(om / eta, h) * std::abs(i.dot(h)) / length2;
}

// Rough exit: h_B is a visible normal of o, o refracts into the slab (never totally reflected)
// and the in-slab direction leaves the flat entry along i. dw_h / dw_i is Walter's refraction
// Jacobian times the flat interface's dw_t / dw_i = |i.z| / (eta^2 t.z), which together give
// |im.h| |i.z| / (im.z |im - o|^2).
std::optional<Vec3> SampleRoughExit(const Ndf& proposal, double eta, const Vec3& o, const Vec2& u) {
  if (o.z() < kMinRoughExitCosine) return std::nullopt;
  const NormalSample s = proposal.SampleVisibleNormal(o, u);
  if (!(s.pdf > 0) || s.h.dot(o) <= 0) return std::nullopt;
  const std::optional<Vec3> into_slab = Refract(o, s.h, 1.0 / eta);
  if (!into_slab || into_slab->z() >= 0) return std::nullopt;
  const Vec3 im = -eta * into_slab->normalized();  // eta times the light's in-slab direction
  const double sin2 = im.x() * im.x() + im.y() * im.y();
  if (sin2 >= 1.0) return std::nullopt;  // totally reflected at the flat entry
  return Vec3(-im.x(), -im.y(), -std::sqrt(1.0 - sin2));
}

double RoughExitPdf(const Ndf& proposal, double eta, const Vec3& i, const Vec3& o) {
  const Vec3 im(-i.x(), -i.y(), std::sqrt(std::max(0.0, eta * eta - i.x() * i.x() - i.y() * i.y())));
  if (o.z() < kMinRoughExitCosine) return 0.0;
  const Vec3 difference = im - o;
  const double length2 = difference.squaredNorm();
  if (!(length2 > 0)) return 0.0;
  const Vec3 h = difference / std::sqrt(length2);
  if (h.z() <= 0 || im.dot(h) <= 0 || o.dot(h) <= 0) return 0.0;
  return proposal.VisibleNormalPdf(o, h) * im.dot(h) * std::abs(i.z()) / (im.z() * length2);
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// DualMicrofacetBsdf

DualMicrofacetBsdf::DualMicrofacetBsdf(const Ndf& ndf, const DualMicrofacetParams& params, const Ndf* proposal)
    : ndf_(ndf), proposal_(proposal ? *proposal : ndf), params_(params), model_(params.eta, params.shadowing) {}

DualMicrofacetBsdf::LobeWeights DualMicrofacetBsdf::lobe_weights(bool viewer_below) const {
  const double alpha = viewer_below ? 1.0 - params_.alpha : params_.alpha;
  LobeWeights w;
  w.diffuse = DiffuseProbability(params_.k_s, params_.rho_d);
  // The internal-reflection halo is broad and covered by the cosine alone: give it a fifth.
  if (params_.internal_reflection) w.diffuse = std::max(w.diffuse, kInternalReflectionCosineShare);
  // Both configurations keep a tenth of the specular samples: for 0 < alpha < 1 the blend lives
  // where both are non-zero, and each sampler covers its own configuration's support.
  w.rough_entry = (1.0 - w.diffuse) * std::clamp(alpha, 0.1, 0.9);
  w.rough_exit = (1.0 - w.diffuse) - w.rough_entry;
  return w;
}

Rgb DualMicrofacetBsdf::EvalAbove(const Vec3& i, const Vec3& o, double alpha) const {
  double rho = model_.Rho(ndf_, alpha, i, o);
  if (params_.internal_reflection) rho += InternalReflection(params_.eta).Blend(ndf_, alpha, i, o);
  const Rgb& k = params_.k_s;
  const Rgb& d = params_.rho_d;
  return {k[0] * rho + d[0], k[1] * rho + d[1], k[2] * rho + d[2]};
}

Rgb DualMicrofacetBsdf::Eval(const Vec3& wi, const Vec3& wo) const {
  if (!OppositeSides(wi, wo)) return {0, 0, 0};
  if (wo.z() > 0) return EvalAbove(wi, wo, params_.alpha);
  return EvalAbove(FlipZ(wi), FlipZ(wo), 1.0 - params_.alpha);
}

double DualMicrofacetBsdf::PdfAbove(const Vec3& i, const Vec3& o, const LobeWeights& weights) const {
  double pdf = weights.diffuse * std::abs(i.z()) * kInvPi;
  if (weights.rough_entry > 0) pdf += weights.rough_entry * RoughEntryPdf(proposal_, params_.eta, i, o);
  if (weights.rough_exit > 0) pdf += weights.rough_exit * RoughExitPdf(proposal_, params_.eta, i, o);
  return pdf;
}

double DualMicrofacetBsdf::Pdf(const Vec3& wi, const Vec3& wo) const {
  if (!OppositeSides(wi, wo)) return 0.0;
  const bool below = wo.z() < 0;
  return below ? PdfAbove(FlipZ(wi), FlipZ(wo), lobe_weights(true)) : PdfAbove(wi, wo, lobe_weights(false));
}

std::optional<BsdfSample> DualMicrofacetBsdf::Sample(const Vec3& wo, double u_lobe, const Vec2& u) const {
  if (wo.z() == 0) return std::nullopt;
  const bool below = wo.z() < 0;
  const Vec3 o = below ? FlipZ(wo) : wo;
  const LobeWeights weights = lobe_weights(below);
  std::optional<Vec3> i;
  if (u_lobe < weights.diffuse) {
    i = SampleCosineTransmission(o, u);
  } else if (u_lobe < weights.diffuse + weights.rough_entry) {
    i = SampleRoughEntry(proposal_, params_.eta, o, u);
  } else {
    i = SampleRoughExit(proposal_, params_.eta, o, u);
  }
  if (!i) return std::nullopt;
  return Finish(*this, below ? FlipZ(*i) : *i, wo);
}

// ---------------------------------------------------------------------------------------------
// WalterBsdf

WalterBsdf::WalterBsdf(const Ndf& ndf, double eta_i, double eta_o, const Rgb& k_s, const Rgb& rho_d, double azimuth)
    : ndf_(ndf),
      eta_i_(eta_i),
      eta_o_(eta_o),
      k_s_(k_s),
      rho_d_(rho_d),
      cos_azimuth_(std::cos(azimuth)),
      sin_azimuth_(std::sin(azimuth)),
      diffuse_probability_(DiffuseProbability(k_s, rho_d)) {}

// Turning by -azimuth about z, as BaselineShape does (fit/baseline_fit.cc), after mirroring a
// viewer below to above.
Vec3 WalterBsdf::ToLobe(const Vec3& v) const {
  return {cos_azimuth_ * v.x() + sin_azimuth_ * v.y(), -sin_azimuth_ * v.x() + cos_azimuth_ * v.y(), v.z()};
}

Vec3 WalterBsdf::FromLobe(const Vec3& v) const {
  return {cos_azimuth_ * v.x() - sin_azimuth_ * v.y(), sin_azimuth_ * v.x() + cos_azimuth_ * v.y(), v.z()};
}

Rgb WalterBsdf::Eval(const Vec3& wi, const Vec3& wo) const {
  if (!OppositeSides(wi, wo)) return {0, 0, 0};
  const bool below = wo.z() < 0;
  const Vec3 i = ToLobe(below ? FlipZ(wi) : wi), o = ToLobe(below ? FlipZ(wo) : wo);
  const double f = WalterBtdf(ndf_, i, o, eta_i_, eta_o_);
  return {k_s_[0] * f + rho_d_[0], k_s_[1] * f + rho_d_[1], k_s_[2] * f + rho_d_[2]};
}

// h = normalize(-(eta_i i + eta_o o)) turned up, a visible normal of o; dw_h / dw_i =
// eta_i^2 |i.h| / (eta_i i.h + eta_o o.h)^2 (Walter et al. 2007 eq. 17).
double WalterBsdf::RefractionPdf(const Vec3& i, const Vec3& o) const {
  Vec3 h = -(eta_i_ * i + eta_o_ * o);
  const double length2 = h.squaredNorm();
  if (!(length2 > 0)) return 0.0;
  h /= std::sqrt(length2);
  if (h.z() < 0) h = -h;
  const double cos_ih = i.dot(h), cos_oh = o.dot(h);
  if (cos_oh <= 0 || cos_ih >= 0) return 0.0;
  const double denominator = eta_i_ * cos_ih + eta_o_ * cos_oh;
  return ndf_.VisibleNormalPdf(o, h) * eta_i_ * eta_i_ * std::abs(cos_ih) / (denominator * denominator);
}

double WalterBsdf::Pdf(const Vec3& wi, const Vec3& wo) const {
  if (!OppositeSides(wi, wo)) return 0.0;
  const bool below = wo.z() < 0;
  const Vec3 i = ToLobe(below ? FlipZ(wi) : wi), o = ToLobe(below ? FlipZ(wo) : wo);
  return diffuse_probability_ * std::abs(i.z()) * kInvPi + (1.0 - diffuse_probability_) * RefractionPdf(i, o);
}

std::optional<BsdfSample> WalterBsdf::Sample(const Vec3& wo, double u_lobe, const Vec2& u) const {
  if (wo.z() == 0) return std::nullopt;
  const bool below = wo.z() < 0;
  const Vec3 o = ToLobe(below ? FlipZ(wo) : wo);
  std::optional<Vec3> i;
  if (u_lobe < diffuse_probability_) {
    i = SampleCosineTransmission(o, u);
  } else {
    const NormalSample s = ndf_.SampleVisibleNormal(o, u);
    if (!(s.pdf > 0) || s.h.dot(o) <= 0) return std::nullopt;
    i = Refract(o, s.h, eta_o_ / eta_i_);
    if (!i || i->z() >= 0) return std::nullopt;
    i = i->normalized();
  }
  const Vec3 wi = FromLobe(*i);
  return Finish(*this, below ? FlipZ(wi) : wi, wo);
}

// ---------------------------------------------------------------------------------------------
// SlabLobeBsdf

namespace {

SlabLobeParams TurnedOver(SlabLobeParams p) {
  std::swap(p.kappa_entry, p.kappa_exit);
  return p;
}

// A direction of the vMF lobe about `mean` (Jakob 2012's stable inversion of the polar cosine).
Vec3 SampleVmf(const Vec3& mean, double kappa, const Vec2& u) {
  const double w = 1.0 + std::log(u.x() + (1.0 - u.x()) * std::exp(-2.0 * kappa)) / kappa;
  const double r = std::sqrt(std::max(0.0, 1.0 - w * w));
  Vec3 t, b;
  OrthonormalBasis(mean, &t, &b);
  return (w * mean + r * (std::cos(kTwoPi * u.y()) * t + std::sin(kTwoPi * u.y()) * b)).normalized();
}

}  // namespace

SlabLobeBsdf::SlabLobeBsdf(const SlabLobeParams& lobe, const Rgb& k_s, const Rgb& rho_d)
    : above_(lobe), below_(TurnedOver(lobe)), k_s_(k_s), rho_d_(rho_d),
      diffuse_probability_(DiffuseProbability(k_s, rho_d)) {
  if (!std::isfinite(lobe.kappa_entry) && !std::isfinite(lobe.kappa_exit)) {
    common::ThrowInvalidInput("kappa", "a slab lobe needs at least one rough interface (a smooth slab is a delta)");
  }
}

Rgb SlabLobeBsdf::Eval(const Vec3& wi, const Vec3& wo) const {
  if (!OppositeSides(wi, wo)) return {0, 0, 0};
  const double rho = wo.z() > 0 ? above_.Rho(wi, wo) : below_.Rho(FlipZ(wi), FlipZ(wo));
  return {k_s_[0] * rho + rho_d_[0], k_s_[1] * rho + rho_d_[1], k_s_[2] * rho + rho_d_[2]};
}

double SlabLobeBsdf::Pdf(const Vec3& wi, const Vec3& wo) const {
  if (!OppositeSides(wi, wo)) return 0.0;
  const SlabLobeModel& lobe = wo.z() > 0 ? above_ : below_;
  const Vec3 o = wo.z() > 0 ? wo : FlipZ(wo);
  const double kappa = lobe.LightConcentration(o);
  return diffuse_probability_ * std::abs(wi.z()) * kInvPi + (1.0 - diffuse_probability_) * VmfDensity(kappa, -wi.dot(wo));
}

std::optional<BsdfSample> SlabLobeBsdf::Sample(const Vec3& wo, double u_lobe, const Vec2& u) const {
  if (wo.z() == 0) return std::nullopt;
  Vec3 wi;
  if (u_lobe < diffuse_probability_) {
    wi = SampleCosineTransmission(wo, u);
  } else {
    const SlabLobeModel& lobe = wo.z() > 0 ? above_ : below_;
    wi = SampleVmf(-wo, lobe.LightConcentration(wo.z() > 0 ? wo : FlipZ(wo)), u);
    if (!OppositeSides(wi, wo)) return std::nullopt;  // the lobe's mass beyond the horizon
  }
  return Finish(*this, wi, wo);
}

// ---------------------------------------------------------------------------------------------
// SlabBsdf

SlabBsdf::SlabBsdf(const Ndf& entry, const Ndf& exit, double eta, const Rgb& k_s, const Rgb& rho_d,
                   const SlabInternalLight& internal)
    : entry_(entry),
      exit_(exit),
      eta_(eta),
      k_s_(k_s),
      rho_d_(rho_d),
      internal_(internal),
      diffuse_probability_(DiffuseProbability(k_s, rho_d)) {
  DualMicrofacetModel validate_eta(eta);
  for (const double weight : {internal.weight, internal.longer_weight}) {
    if (!(weight >= 0) || !std::isfinite(weight)) {
      common::ThrowInvalidInput("internal reflection", "its weights must be finite and >= 0");
    }
  }
  if (internal.longer_weight > 0 && (!internal.longer_entry || !internal.longer_exit)) {
    common::ThrowInvalidInput("internal reflection", "a weight of the longer paths needs their widened NDFs");
  }
  // The halo is broad and covered by the cosine alone: give it a fifth, as DualMicrofacetBsdf does.
  if (internal.weight > 0 || internal.longer_weight > 0) {
    diffuse_probability_ = std::max(diffuse_probability_, kInternalReflectionCosineShare);
  }
}

Rgb SlabBsdf::Eval(const Vec3& wi, const Vec3& wo) const {
  if (!OppositeSides(wi, wo)) return {0, 0, 0};
  const bool below = wo.z() < 0;
  const Ndf& entry = below ? exit_ : entry_;
  const Ndf& exit = below ? entry_ : exit_;
  const Vec3 i = below ? FlipZ(wi) : wi, o = below ? FlipZ(wo) : wo;
  double rho = SlabTransmission(entry, exit, eta_).Rho(i, o);
  if (internal_.weight > 0) rho += internal_.weight * SlabInternalReflection(entry, exit, eta_).Rho(i, o);
  if (internal_.longer_weight > 0) {
    const Ndf& longer_entry = below ? *internal_.longer_exit : *internal_.longer_entry;
    const Ndf& longer_exit = below ? *internal_.longer_entry : *internal_.longer_exit;
    rho += internal_.longer_weight * SlabInternalReflection(longer_entry, longer_exit, eta_).Rho(i, o);
  }
  return {k_s_[0] * rho + rho_d_[0], k_s_[1] * rho + rho_d_[1], k_s_[2] * rho + rho_d_[2]};
}

// Half of the specular draws go to each side's configuration: the slab's lobe is their
// convolution, at least as wide as either, and whichever side is rougher shapes most of it.
double SlabBsdf::PdfAbove(const Ndf& entry, const Ndf& exit, const Vec3& i, const Vec3& o) const {
  const double specular = 0.5 * (1.0 - diffuse_probability_);
  return diffuse_probability_ * std::abs(i.z()) * kInvPi + specular * RoughEntryPdf(entry, eta_, i, o) +
         specular * RoughExitPdf(exit, eta_, i, o);
}

double SlabBsdf::Pdf(const Vec3& wi, const Vec3& wo) const {
  if (!OppositeSides(wi, wo)) return 0.0;
  if (wo.z() < 0) return PdfAbove(exit_, entry_, FlipZ(wi), FlipZ(wo));
  return PdfAbove(entry_, exit_, wi, wo);
}

std::optional<BsdfSample> SlabBsdf::Sample(const Vec3& wo, double u_lobe, const Vec2& u) const {
  if (wo.z() == 0) return std::nullopt;
  const bool below = wo.z() < 0;
  const Vec3 o = below ? FlipZ(wo) : wo;
  const Ndf& entry = below ? exit_ : entry_;
  const Ndf& exit = below ? entry_ : exit_;
  std::optional<Vec3> i;
  if (u_lobe < diffuse_probability_) {
    i = SampleCosineTransmission(o, u);
  } else if (u_lobe < diffuse_probability_ + 0.5 * (1.0 - diffuse_probability_)) {
    i = SampleRoughEntry(entry, eta_, o, u);
  } else {
    i = SampleRoughExit(exit, eta_, o, u);
  }
  if (!i) return std::nullopt;
  return Finish(*this, below ? FlipZ(*i) : *i, wo);
}

// ---------------------------------------------------------------------------------------------
// EvaluatedBsdf

Rgb EvaluatedBsdf::Eval(const Vec3& wi, const Vec3& wo) const {
  if (!OppositeSides(wi, wo)) return {0, 0, 0};
  return wo.z() > 0 ? evaluate_(wi, wo) : evaluate_(FlipZ(wi), FlipZ(wo));
}

double EvaluatedBsdf::Pdf(const Vec3& wi, const Vec3& wo) const { return CosineTransmissionPdf(wi, wo); }

std::optional<BsdfSample> EvaluatedBsdf::Sample(const Vec3& wo, double, const Vec2& u) const {
  if (wo.z() == 0) return std::nullopt;
  return Finish(*this, SampleCosineTransmission(wo, u), wo);
}

}  // namespace svbtdf::model
