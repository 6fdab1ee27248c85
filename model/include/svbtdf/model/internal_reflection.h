#pragma once
// Light reflected inside the slab: the paths that are transmitted by the entry, reflected once by
// the exit and once by the entry from inside, and transmitted by the exit (T R R T, four interface
// hits), for the dual-microfacet model's two virtual configurations (docs/model.md, "Light
// reflected inside the slab").
//
// Conventions of docs/model.md: i toward the light (i.z < 0), o toward the camera (o.z > 0),
// eta = n_slab / n_air > 1. Each configuration has one rough interface with the NDF D and one flat
// one. With the rough entry, for the in-slab direction t2 = om / eta that leaves the flat exit
// along o,
//
//   IR_T(i, o) = (1 - F(o.z)) / (eta^2 |i.z|) * integral over the entry's normals h1 of
//       D(h1) |i.h1| (1 - F(|i.h1|)) G1(i, h1) G1(d, h1)      (refraction into d, travelling up)
//       * F_flat(d)                                            (reflection at the flat exit)
//       * f_R(w, t2)                                           (reflection at the entry, inside)
//
// with d = i refracted through -h1, w = (-d.x, -d.y, d.z), and f_R the microfacet BRDF of the
// entry seen from inside, F(w.h2) D(h2) G1(w, h2) G1(t2, h2) / (4 w.z t2.z), h2 = normalize(w +
// t2). The integral over d was changed into one over h1 (Walter et al. 2007 eq. 17), where the
// integrand is as smooth as D; it is evaluated on fixed polar nodes about z. Shadowing is the
// NDF's own Smith G1 (the Monte Carlo tracer's), not the model's separable alpha_b term.
//
// The rough-exit configuration follows by the slab's reciprocity: turned over (z -> -z) with light
// and camera swapped, a rough exit is a rough entry whose NDF is turned by half a turn about z,
//   IR_B[D](i, o) = IR_T[D'](flip(o), flip(i)),   D'(h) = D(-h.x, -h.y, h.z).

#include <vector>

#include "svbtdf/model/ndf.h"
#include "svbtdf/model/vec.h"

namespace svbtdf::model {

// Polar nodes of the integral over h1: `radial` x `azimuthal` nodes at theta = (pi/2) s^2.
struct InternalReflectionQuadrature {
  int radial = 24;
  int azimuthal = 24;
};

class InternalReflection {
 public:
  using Quadrature = InternalReflectionQuadrature;

  // Throws svbtdf::common::Error(kInvalidInput) unless eta is finite and > 1. The default
  // quadrature's nodes are built once per process, so construction is cheap.
  explicit InternalReflection(double eta, Quadrature quadrature = {});

  double eta() const { return eta_; }

  // The T R R T paths of the rough-entry, flat-exit configuration; 0 unless i.z < 0 < o.z.
  double RoughEntry(const Ndf& ndf, const Vec3& i, const Vec3& o) const;
  // The same for the flat-entry, rough-exit configuration.
  double RoughExit(const Ndf& ndf, const Vec3& i, const Vec3& o) const;
  // Blended as the direct terms are: exp(alpha ln IR_T + (1 - alpha) ln IR_B) (LogBlend).
  double Blend(const Ndf& ndf, double alpha, const Vec3& i, const Vec3& o) const;

  struct Node {
    Vec3 h;
    double solid_angle;
  };

 private:
  double eta_;
  const std::vector<Node>* nodes_;
};

}  // namespace svbtdf::model
