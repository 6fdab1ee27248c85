#pragma once
// "The BTDF of texel x": what the rig's renderer needs from a ground truth. Two truths implement
// it: the analytic dual-microfacet TruthMaterial (truth_material.h) and the Monte Carlo slab
// truth (montecarlo_truth.h). The renderer depends only on this interface, so the measurement
// equation and the quadrature are the same whichever truth is rendered.

#include "svbtdf/model/dual_microfacet.h"
#include "svbtdf/model/vec.h"

namespace svbtdf::simulate {

class SpatialBtdf {
 public:
  virtual ~SpatialBtdf() = default;

  virtual int texels_x() const = 0;
  virtual int texels_y() const = 0;
  int Index(int col, int row) const { return row * texels_x() + col; }
  int num_texels() const { return texels_x() * texels_y(); }

  // R(x, i, o) RGB of texel `index` for unit i (toward the light, i.z < 0) and o (toward the
  // camera, o.z > 0), including any diffuse part.
  virtual model::Rgb Evaluate(int index, const model::Vec3& i, const model::Vec3& o) const = 0;

  // The same for linearly polarised light whose unit electric field `field` is transverse to its
  // travel direction -i (a polarised monitor, docs/simulator.md "A polarised LCD"). A truth that
  // cannot tell polarisations apart throws svbtdf::Error(kInvalidInput).
  virtual model::Rgb EvaluatePolarised(int index, const model::Vec3& i, const model::Vec3& o,
                                       const model::Vec3& field) const;

  // How sharp the texel's lobe can be, as a microfacet roughness: the renderer chooses its rule
  // over a dot's disk by the ratio of the dot's angular radius to this (DotRule).
  virtual double MinRoughness(int index) const = 0;

  // How far into its lobe's tail light from direction i falls, seen along o: the lobe's value
  // there as a fraction of its peak, for a lobe whose derivatives fall with that fraction as a GGX
  // lobe's do (DotRule); 1 where the truth cannot say, which leaves the rule to the ratio alone.
  virtual double LobeFraction(int index, const model::Vec3& i, const model::Vec3& o) const { return 1.0; }
};

}  // namespace svbtdf::simulate
