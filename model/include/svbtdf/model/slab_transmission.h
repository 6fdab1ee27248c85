#pragma once
// The light a slab with two rough interfaces transmits straight through: refracted by the entry
// into the slab, carried across it, refracted by the exit toward the camera, with no reflection
// on the way (the T T paths, two interface hits). With one interface flat this is exactly the
// dual-microfacet configuration of that side (rho_T for a rough entry, rho_B for a rough exit);
// with both rough it is their convolution, which no single-NDF configuration holds
// (docs/model.md, "Two rough interfaces").
//
// Conventions of docs/model.md: i toward the light (i.z < 0), o toward the camera (o.z > 0),
// eta = n_slab / n_air > 1, each interface's facet normals on the upper hemisphere with the NDF's
// own Smith G1 (the Monte Carlo tracer's microsurfaces). For the in-slab direction d (travelling
// up, d.z > 0),
//
//   rho(i, o) = integral over d of f_entry(i, d) f_exit(-d, o) |d.z| exp(-tau / d.z) d omega_d
//
// with f_entry Walter's BTDF from air into the slab and f_exit the one from the slab into air
// (WalterBtdf). The integral is taken by two fixed sets of directions, each importance-sampled by
// one interface: the exit's normals visible from o (refracted into d) and the entry's visible
// from the light (refracted into d), combined by the balance heuristic. Each set is an n x n grid
// of stratum centres pushed through the NDF's visible-normal sampler, so rho is a smooth,
// deterministic function of i, o and the NDFs' parameters (what a fit's derivatives need), and a
// narrow interface on either side is resolved by the set that samples it.

#include <vector>

#include "svbtdf/model/internal_reflection.h"
#include "svbtdf/model/ndf.h"
#include "svbtdf/model/vec.h"

namespace svbtdf::model {

// n x n stratum centres per interface (2 n^2 evaluations of the integrand per rho).
struct SlabTransmissionQuadrature {
  int per_axis = 8;
};

class SlabTransmission {
 public:
  using Quadrature = SlabTransmissionQuadrature;

  // The NDFs are referenced, not copied: the caller keeps them alive. Throws
  // svbtdf::common::Error(kInvalidInput) unless eta is finite and > 1, the optical depth finite
  // and >= 0, and the quadrature has at least 2 points per axis.
  SlabTransmission(const Ndf& entry, const Ndf& exit, double eta, double optical_depth = 0.0, Quadrature quadrature = {});

  double eta() const { return eta_; }
  double optical_depth() const { return optical_depth_; }

  // rho of the T T paths for a light direction i (i.z < 0) and a viewer o (o.z > 0); 0 otherwise.
  double Rho(const Vec3& i, const Vec3& o) const;

  // rho at many light directions for one viewer (below).
  class ForViewer;
  ForViewer Viewer(const Vec3& o) const;

 private:
  // Density of the in-slab direction d under each interface's sampling.
  double EntryPdf(const Vec3& i, const Vec3& d) const;
  double ExitPdf(const Vec3& o, const Vec3& d) const;
  double Attenuation(const Vec3& d) const;

  const Ndf& entry_;
  const Ndf& exit_;
  double eta_;
  double optical_depth_;
  int per_axis_;
};

// rho at many light directions for one viewer: the exit's directions depend only on o, so they
// are found once (what a fit of one texel, whose view is fixed, evaluates over and over). It
// holds a copy of the slab, so it may outlive it (not the NDFs).
class SlabTransmission::ForViewer {
 public:
  double Rho(const Vec3& i) const;

 private:
  friend class SlabTransmission;
  struct ExitNode {
    Vec3 d;         // in-slab direction, travelling up
    double value;   // f_exit(-d, o) |d.z| exp(-tau / d.z)
    double pdf;     // density of d under the exit's sampling
  };
  ForViewer(const SlabTransmission& slab, const Vec3& o) : slab_(slab), o_(o) {}
  SlabTransmission slab_;
  Vec3 o_;
  std::vector<ExitNode> exit_nodes_;
};

// The shape of the light a slab with two rough interfaces reflects inside before it leaves toward
// the camera (T R R T and longer paths), which SlabTransmission leaves out: the one-rough-side
// T R R T terms of each side (internal_reflection.h) summed, IR_T[entry] + IR_B[exit]. Each term is
// exact when the other side is flat; with both sides rough it is an approximation of the
// four-hit halo's shape, and with a fitted weight it stands for every internal path (measured
// against the Monte Carlo slab in docs/model.md, "Two rough interfaces").
//
// Light trapped by total internal reflection makes more round trips than the one this shape
// follows, each adding a rough reflection, so its halo is wider: the slab model stands for those
// longer paths with a second shape, this one with each rough side's roughness times
// kLongerPathsWidening (docs/model.md, "Two rough interfaces"). sqrt(2): the T R R T shape meets
// the rough side twice, and slopes' variances add, so twice the variance per meeting is the
// spread of four rough events, a path with one or two round trips more. Fixed before it was
// measured against the Monte Carlo slab, not fitted to it.
inline constexpr double kLongerPathsWidening = 1.4142135623730951;  // sqrt(2)

class SlabInternalReflection {
 public:
  // The NDFs are referenced, not copied. Throws svbtdf::common::Error(kInvalidInput) unless eta
  // is finite and > 1.
  SlabInternalReflection(const Ndf& entry, const Ndf& exit, double eta);
  // 0 unless i.z < 0 < o.z.
  double Rho(const Vec3& i, const Vec3& o) const;

 private:
  const Ndf& entry_;
  const Ndf& exit_;
  InternalReflection paths_;
};

}  // namespace svbtdf::model
