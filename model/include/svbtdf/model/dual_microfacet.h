#pragma once
// The dual-microfacet BTDF of a thin slab (Dai et al. 2009), in the convention of docs/model.md:
// z is the macro normal pointing toward the camera, i points toward the light (i.z < 0), o toward
// the camera (o.z > 0), eta = n_slab / n_air > 1.
//
// The slab is approximated by two virtual configurations, each with one rough and one flat
// interface, blended in log space:
//   rho_T  rough entry (the side facing the light), flat exit   (the paper's rho_t)
//   rho_B  flat entry, rough exit (the side facing the camera)   (the paper's rho_b)
//   ln rho = alpha ln rho_T + (1 - alpha) ln rho_B
// Both configurations share one NDF D. Fitting needs everything but D, so the model exposes each
// configuration as (h, factor) with rho = factor * D(h).

#include <array>
#include <optional>

#include "svbtdf/model/ndf.h"
#include "svbtdf/model/shadowing.h"
#include "svbtdf/model/vec.h"

namespace svbtdf::model {

// One virtual configuration evaluated for a pair of directions, without the NDF.
struct VirtualConfiguration {
  bool valid = false;  // false where no facet of the upper hemisphere transmits i into o
  Vec3 h = Vec3::UnitZ();  // generalised half vector at the rough interface (h.z > 0)
  double factor = 0.0;     // rho = factor * D(h): Fresnel, shadowing and Jacobian terms
};

class DualMicrofacetModel {
 public:
  // Throws svbtdf::Error(kInvalidInput) unless eta is finite and > 1.
  explicit DualMicrofacetModel(double eta, SmithShadowing shadowing = SmithShadowing::None());

  double eta() const { return eta_; }
  const SmithShadowing& shadowing() const { return shadowing_; }

  // Rough entry, flat exit: om = (o.x, o.y, sqrt(eta^2 - |o_xy|^2)), h_T = normalize(i + om),
  //   rho_T = (1-F(|i.h|)) (1-F(o.z)) G(i, t, h) D(h) |i.h| |om.h| / (|i.z| om.z |i + om|^2)
  // with t = om / eta the in-slab direction.
  //
  // `field`: for linearly polarised light, its unit electric field, transverse to the travel
  // direction -i (polarisation.h, TransverseField). The Fresnel product (1 - F_entry)(1 - F_exit)
  // is then the power the two interfaces transmit of that field (TwoInterfaceTransmittance, each
  // facet's own plane of incidence); null: unpolarised light, the product of the unpolarised
  // transmittances (docs/model.md, "Polarised light").
  VirtualConfiguration RoughEntry(const Vec3& i, const Vec3& o, const Vec3* field = nullptr) const;

  // Flat entry, rough exit: im = (-i.x, -i.y, sqrt(eta^2 - |i_xy|^2)), h_B = normalize(im - o),
  //   rho_B = (1-F(|i.z|)) (1-F(|o.h|)) G(-im/eta, o, h) D(h) |im.h| |o.h| / (im.z o.z |im - o|^2)
  VirtualConfiguration RoughExit(const Vec3& i, const Vec3& o, const Vec3* field = nullptr) const;

  // The two configurations' half vectors alone, {h_T, h_B}, without their Fresnel, shadowing and
  // Jacobian terms: where in D a pair of directions falls, at a fraction of RoughEntry's and
  // RoughExit's cost. A configuration that is not valid for (i, o) gives nullopt.
  std::array<std::optional<Vec3>, 2> HalfVectors(const Vec3& i, const Vec3& o) const;

  double RhoT(const Ndf& ndf, const Vec3& i, const Vec3& o, const Vec3* field = nullptr) const;
  double RhoB(const Ndf& ndf, const Vec3& i, const Vec3& o, const Vec3* field = nullptr) const;
  // The blended model with weight alpha in [0, 1] on the rough-entry term.
  double Rho(const Ndf& ndf, double alpha, const Vec3& i, const Vec3& o, const Vec3* field = nullptr) const;

 private:
  double eta_;
  SmithShadowing shadowing_;
};

// exp(alpha ln rho_T + (1 - alpha) ln rho_B), with the limits alpha = 0 -> rho_B and
// alpha = 1 -> rho_T taken exactly (so a zero in the unused term does not matter).
double LogBlend(double rho_T, double rho_B, double alpha);

// Walter et al. 2007 single-interface microfacet BTDF (their eq. 21) for light arriving along
// i in a medium of index eta_i and leaving along o in a medium of index eta_o, i and o on opposite
// sides of the macro surface; G is the NDF's own Smith G1 product. Used as the baseline the paper
// compares against and by the Monte Carlo tracer's tests.
double WalterBtdf(const Ndf& ndf, const Vec3& i, const Vec3& o, double eta_i, double eta_o);

using Rgb = std::array<double, 3>;

// The grey value fitting and comparison work on: the mean of the channels (the fit recovers the
// per-channel scale k_s afterwards, so any fixed positive weighting would do).
inline double Luminance(const Rgb& rgb) { return (rgb[0] + rgb[1] + rgb[2]) / 3.0; }

// Everything one texel of a fitted material needs besides its NDF (paper Sec. 4):
//   R(i, o)[c] = k_s[c] * rho(i, o) + rho_d[c].
struct DualMicrofacetParams {
  double eta = 1.5;
  double alpha = 0.5;
  SmithShadowing shadowing = SmithShadowing::None();
  Rgb k_s = {1.0, 1.0, 1.0};
  Rgb rho_d = {0.0, 0.0, 0.0};
  // Adds the light reflected once by each interface inside the slab (T R R T paths,
  // internal_reflection.h) to rho, blended with the same alpha: rho + LogBlend(IR_T, IR_B, alpha).
  bool internal_reflection = false;
};

// rho(i, o) of the texel's specular part: the blend, plus the internal-reflection term when the
// params ask for it.
double SpecularRho(const Ndf& ndf, const DualMicrofacetParams& params, const Vec3& i, const Vec3& o);

Rgb EvaluateMaterial(const Ndf& ndf, const DualMicrofacetParams& params, const Vec3& i,
                     const Vec3& o);

}  // namespace svbtdf::model
