#pragma once
// The normal distribution function (NDF) interface shared by the analytic NDFs, the tabulated
// hemicube NDF that fitting recovers, the dual-microfacet BTDF and the Monte Carlo slab tracer.
//
// Conventions (docs/model.md): normals h live on the upper hemisphere (h.z > 0) of the sample
// frame whose z axis is the macro normal. D is a density per solid angle normalised by the
// projected-area condition
//     integral over the upper hemisphere of D(h) h.z d(omega_h) = 1,
// and D(h) = 0 for h.z <= 0.

#include <memory>
#include <string>

#include "svbtdf/model/vec.h"

namespace svbtdf::model {

// One normal drawn from the distribution of normals visible from a direction v.
struct NormalSample {
  Vec3 h;         // unit normal, h.z > 0 and h.v > 0
  double pdf;     // density of h per solid angle under the sampler actually used
  // Monte Carlo weight of the sample for the visible-normal integral,
  //   weight = G1(v, h) (v.h) D(h) / (v.z pdf).
  // It is exactly 1 for exact visible-normal samplers (GGX, Beckmann) and <= 1 for the
  // Ellipsoid NDF, whose G1 is clamped at 1 (Walter et al. 2016, Sec. 3).
  double weight;
};

class Ndf {
 public:
  virtual ~Ndf() = default;

  // Short identifier, e.g. "ggx", "beckmann", "ellipsoid", "vmf", "tabulated".
  virtual std::string name() const = 0;

  // Normal density D(h) for a unit h; zero for h.z <= 0.
  virtual double D(const Vec3& h) const = 0;

  // Smith monodirectional masking of this NDF's own microsurface for a unit direction v on
  // either side of the surface (it uses sign(v.z) v, as in Walter et al. 2007 eq. 23, and
  // returns 0 where the facet h is back-facing to that direction).
  virtual double G1(const Vec3& v, const Vec3& h) const = 0;

  // Draws a normal from the normals visible from v (v.z > 0) with u uniform on [0,1)^2.
  virtual NormalSample SampleVisibleNormal(const Vec3& v, const Vec2& u) const = 0;

  // Density per solid angle with which SampleVisibleNormal(v, .) returns h.
  virtual double VisibleNormalPdf(const Vec3& v, const Vec3& h) const = 0;

  virtual std::unique_ptr<Ndf> Clone() const = 0;
};

}  // namespace svbtdf::model
