#pragma once
// BSDFs in the shape renderers expect (Mitsuba 3's and pbrt-v4's interfaces): Eval, Sample and
// Pdf for one point of a surface, in the sample frame of docs/model.md (z is the macro normal).
//
// Directions point away from the surface: wo toward the viewer, wi toward the light. The models
// here transmit only: Eval is zero unless wi and wo lie on opposite sides. A viewer below the
// sample (wo.z < 0) sees the slab mirrored: docs/render.md says how each BSDF treats that side.
//
// Renderers build one BSDF per surface hit, so construction must be cheap: the BSDFs hold a
// reference to an NDF that the caller keeps alive (a material's tables, built once) and never
// allocate.

#include <functional>
#include <optional>

#include "svbtdf/model/dual_microfacet.h"
#include "svbtdf/model/ndf.h"
#include "svbtdf/model/slab_lobe.h"
#include "svbtdf/model/slab_transmission.h"
#include "svbtdf/model/vec.h"

namespace svbtdf::model {

// One direction drawn by Bsdf::Sample.
struct BsdfSample {
  Vec3 wi;     // unit, toward the light, on the other side of the surface from wo
  double pdf;  // solid-angle density of wi under Sample (the same as Pdf(wi, wo))
  Rgb weight;  // Eval(wi, wo) |wi.z| / pdf: the Monte Carlo weight of the sample
};

class Bsdf {
 public:
  virtual ~Bsdf() = default;

  // f(wi, wo) per RGB channel: outgoing radiance along wo per unit irradiance from wi.
  virtual Rgb Eval(const Vec3& wi, const Vec3& wo) const = 0;

  // Draws wi for the viewer direction wo from u_lobe and u uniform on [0, 1). Returns nullopt
  // when the draw carries no light (total internal reflection, a facet turned away): that
  // probability is the mass the pdf lacks, so estimators stay unbiased by counting it as zero.
  virtual std::optional<BsdfSample> Sample(const Vec3& wo, double u_lobe, const Vec2& u) const = 0;

  // The density with which Sample(wo, ...) returns wi.
  virtual double Pdf(const Vec3& wi, const Vec3& wo) const = 0;
};

// The dual-microfacet texel R = k_s rho + rho_d (docs/model.md) with the diffuse part as
// Lambertian transmission. The log-space blend of rho_T and rho_B is not a mixture, so Sample
// draws from a mixture of the two configurations' visible-normal samplers and the cosine, and
// reports that mixture's exact pdf. Seen from below, the slab is mirrored (z -> -z) and the
// blend weight becomes 1 - alpha: the interface the light crosses first is then the other one,
// which makes Eval reciprocal (Eval(wi, wo) = Eval(wo, wi)).
//
// `proposal`, when given, is the NDF whose visible normals Sample draws instead of `ndf`'s: a
// texel whose D is a blend of a material's representatives can sample from a mixture of their
// tables (built once per material) instead of building its own.
class DualMicrofacetBsdf final : public Bsdf {
 public:
  // Throws svbtdf::common::Error(kInvalidInput) unless eta is finite and > 1.
  DualMicrofacetBsdf(const Ndf& ndf, const DualMicrofacetParams& params, const Ndf* proposal = nullptr);

  Rgb Eval(const Vec3& wi, const Vec3& wo) const override;
  std::optional<BsdfSample> Sample(const Vec3& wo, double u_lobe, const Vec2& u) const override;
  double Pdf(const Vec3& wi, const Vec3& wo) const override;

  // How Sample chooses among its three strategies (they sum to 1).
  struct LobeWeights {
    double rough_entry = 0, rough_exit = 0, diffuse = 0;
  };
  LobeWeights lobe_weights(bool viewer_below) const;

 private:
  // Everything with the viewer above (o.z > 0, i.z < 0) and blend weight `alpha`.
  Rgb EvalAbove(const Vec3& i, const Vec3& o, double alpha) const;
  double PdfAbove(const Vec3& i, const Vec3& o, const LobeWeights& weights) const;

  const Ndf& ndf_;
  const Ndf& proposal_;
  DualMicrofacetParams params_;
  DualMicrofacetModel model_;
};

// Walter et al. 2007's single rough interface from a medium of index eta_i (the light's side)
// into one of index eta_o (the viewer's side), times k_s, plus Lambertian transmission rho_d: the
// baseline of `svbtdf fit --model ggx` (R = k_s f_W(i, o) + rho_d). `azimuth` turns the NDF's x
// axis about z. Sample draws the NDF's visible normals from wo and refracts (or the cosine).
class WalterBsdf final : public Bsdf {
 public:
  WalterBsdf(const Ndf& ndf, double eta_i, double eta_o, const Rgb& k_s, const Rgb& rho_d, double azimuth = 0.0);

  Rgb Eval(const Vec3& wi, const Vec3& wo) const override;
  std::optional<BsdfSample> Sample(const Vec3& wo, double u_lobe, const Vec2& u) const override;
  double Pdf(const Vec3& wi, const Vec3& wo) const override;

 private:
  Vec3 ToLobe(const Vec3& v) const;    // sample frame -> the NDF's frame (viewer above)
  Vec3 FromLobe(const Vec3& v) const;  // and back
  double RefractionPdf(const Vec3& i, const Vec3& o) const;  // in the NDF's frame

  const Ndf& ndf_;
  double eta_i_, eta_o_;
  Rgb k_s_, rho_d_;
  double cos_azimuth_, sin_azimuth_;
  double diffuse_probability_;
};

// The analytic slab lobe of seed 000 (slab_lobe.h), R = k_s rho + rho_d, with Lambertian
// transmission as the diffuse part. Sample draws the lobe's vMF about -wo exactly (draws beyond
// the horizon carry no light) or the cosine. Seen from below, the slab is turned over: the two
// interfaces' concentrations swap.
class SlabLobeBsdf final : public Bsdf {
 public:
  // Throws svbtdf::common::Error(kInvalidInput) for bad params or a slab with no rough side.
  SlabLobeBsdf(const SlabLobeParams& lobe, const Rgb& k_s, const Rgb& rho_d);

  Rgb Eval(const Vec3& wi, const Vec3& wo) const override;
  std::optional<BsdfSample> Sample(const Vec3& wo, double u_lobe, const Vec2& u) const override;
  double Pdf(const Vec3& wi, const Vec3& wo) const override;

 private:
  SlabLobeModel above_, below_;  // the viewer above, and below (turned over)
  Rgb k_s_, rho_d_;
  double diffuse_probability_;
};

// The light a slab reflects inside before it leaves, as the slab model holds it: the T R R T
// shape (SlabInternalReflection of the slab's own interfaces) at `weight`, and the longer paths'
// shape (the same with each rough side's NDF widened by kLongerPathsWidening, slab_transmission.h:
// `longer_entry`, `longer_exit`, which the caller makes and keeps alive) at `longer_weight`.
struct SlabInternalLight {
  double weight = 0.0;
  double longer_weight = 0.0;
  const Ndf* longer_entry = nullptr;
  const Ndf* longer_exit = nullptr;
};

// A slab with two rough interfaces (slab_transmission.h), R = k_s (rho_TT + w IR + w' IR') +
// rho_d with IR the light reflected inside it (SlabInternalLight) and Lambertian
// transmission as the diffuse part. rho_TT is an integral, so no sampler of its own has a closed
// pdf: Sample draws from a mixture of the one-rough-side configurations (the entry's normals
// with the exit taken flat, the exit's with the entry flat) and the cosine, and reports that
// mixture's exact pdf. Seen from below, the slab is turned over: the exit becomes the entry.
// The NDFs must look the same turned by half a turn about z (any GGX or Beckmann lobe does);
// the caller keeps them alive.
class SlabBsdf final : public Bsdf {
 public:
  // Throws svbtdf::common::Error(kInvalidInput) unless eta is finite and > 1 and the weights
  // finite and >= 0, with the longer NDFs given where longer_weight > 0.
  SlabBsdf(const Ndf& entry, const Ndf& exit, double eta, const Rgb& k_s, const Rgb& rho_d,
           const SlabInternalLight& internal = {});

  Rgb Eval(const Vec3& wi, const Vec3& wo) const override;
  std::optional<BsdfSample> Sample(const Vec3& wo, double u_lobe, const Vec2& u) const override;
  double Pdf(const Vec3& wi, const Vec3& wo) const override;

 private:
  // With the viewer above: the interface the light crosses first, and the one facing o.
  double PdfAbove(const Ndf& entry, const Ndf& exit, const Vec3& i, const Vec3& o) const;

  const Ndf& entry_;
  const Ndf& exit_;
  double eta_;
  Rgb k_s_, rho_d_;
  SlabInternalLight internal_;
  double diffuse_probability_;
};

// A BSDF known only through evaluations (the Monte Carlo truth's traced slices): Sample draws
// cosine-weighted directions on the other side. `evaluate` takes (i, o) with o.z > 0; a viewer
// below sees the same function mirrored.
class EvaluatedBsdf final : public Bsdf {
 public:
  using Evaluator = std::function<Rgb(const Vec3& i, const Vec3& o)>;
  explicit EvaluatedBsdf(Evaluator evaluate) : evaluate_(std::move(evaluate)) {}

  Rgb Eval(const Vec3& wi, const Vec3& wo) const override;
  std::optional<BsdfSample> Sample(const Vec3& wo, double u_lobe, const Vec2& u) const override;
  double Pdf(const Vec3& wi, const Vec3& wo) const override;

 private:
  Evaluator evaluate_;
};

// Cosine-weighted direction on the side of the surface opposite `wo` (pdf |wi.z| / pi).
Vec3 SampleCosineTransmission(const Vec3& wo, const Vec2& u);

}  // namespace svbtdf::model
