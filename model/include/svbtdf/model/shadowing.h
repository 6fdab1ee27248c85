#pragma once
// The shadowing term of the dual-microfacet model. Dai et al. 2009 (Sec. 4.2) treat shadowing
// as known up to one "shadowing roughness" alpha_b and use Smith's model as in Walter et al.
// 2007; it is deliberately independent of the (tabulated) NDF D so that D stays linear in the
// fit. We use the Smith G1 of a GGX microsurface with roughness alpha_b (Walter et al. 2007
// eq. 34), separable: G(a, b, h) = G1(a, h) G1(b, h).

#include "svbtdf/model/vec.h"

namespace svbtdf::model {

class SmithShadowing {
 public:
  // No shadowing: G = 1 for every front-facing configuration.
  static SmithShadowing None() { return SmithShadowing(-1.0); }
  // GGX Smith shadowing with roughness alpha_b > 0 (the paper starts fitting at 0.2).
  static SmithShadowing Ggx(double roughness);

  bool enabled() const { return roughness_ > 0; }
  double roughness() const { return enabled() ? roughness_ : 0.0; }

  // Monodirectional term for a unit direction v on either side of the interface: it uses the
  // side-adjusted direction sign(v.z) v (Walter et al. 2007 eq. 23, 33) and returns 0 when the
  // facet h is back-facing to it.
  double G1(const Vec3& v, const Vec3& h) const;
  double G(const Vec3& a, const Vec3& b, const Vec3& h) const { return G1(a, h) * G1(b, h); }

 private:
  explicit SmithShadowing(double roughness) : roughness_(roughness) {}
  double roughness_;
};

}  // namespace svbtdf::model
