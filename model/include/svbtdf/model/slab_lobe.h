#pragma once
// The analytic slab lobe of Guo, Qian and Pan 2015 (Sec. 4.3, eqs. 23-24): the light directions
// that a thin slab with two rough interfaces sends toward a fixed viewer, as one von Mises-Fisher
// (vMF) lobe obtained by joint spherical warping of the two interfaces' vMF NDFs.
//
// Conventions of docs/model.md: o toward the camera (o.z > 0), i toward the light (i.z < 0),
// eta = n_slab / n_air > 1; "exit" faces the camera, "entry" the light. Traced from the viewer,
// the exit interface is the first one met (the paper's m_1), the entry the second (m_2). Both mean
// normals are the macro normal z, so the lobe's mean is straight through, i = -o.
//
// For each rough interface the spread of its facet normals (concentration kappa) is carried to the
// light direction by the Jacobian determinant of the map from the facet normal to i with
// everything else at its mean (the chain of eq. 24). The two lobes are combined by matching the
// first moment (eq. 18): A3(kappa_i) = A3(J_exit kappa_exit) A3(J_entry kappa_entry).
// docs/model.md, "The analytic slab lobe", derives the chain; tests/model/slab_lobe_test.cc checks
// every Jacobian by finite differences.

#include <limits>

#include "svbtdf/model/ndf.h"
#include "svbtdf/model/vec.h"

namespace svbtdf::model {

// A flat interface: no spread of its normals.
inline constexpr double kFlatConcentration = std::numeric_limits<double>::infinity();

// A3(kappa) = coth(kappa) - 1 / kappa: the mean cosine to the mean direction of a vMF on the
// sphere (its first moment's length). A3(inf) = 1.
double VmfMeanCosine(double kappa);
// The inverse of VmfMeanCosine on (0, 1]; 1 gives kFlatConcentration.
double VmfConcentrationForMeanCosine(double mean_cosine);

// The vMF density on the whole sphere, kappa / (2 pi (1 - exp(-2 kappa))) exp(kappa (cos - 1)),
// at a direction whose cosine to the mean is `cosine`.
double VmfDensity(double kappa, double cosine);

// The concentration of the vMF whose mean cosine equals the NDF's mean h.z under its projected-area
// density D(h) h.z (the normals a beam at normal incidence meets): moment matching as in the
// paper's eq. 18. For Beckmann of small roughness a this is about 2 / a^2.
double MatchedVmfConcentration(const Ndf& ndf);

// Jacobian determinants of the warps of eq. 24 (|d omega_from / d omega_to|).
// Refraction through a facet m from a medium of index 1 into one of relative index eta (eta < 1
// leaves a denser medium): `from` points away from the facet on the incident side (from.m > 0),
// t = refracted direction, and |d omega_m / d omega_t| = eta^2 |t.m| / (from.m + eta t.m)^2 (the
// paper's eq. 13, Walter et al. 2007 eq. 16). Zero on total internal reflection.
double FacetToRefractedJacobian(const Vec3& from, const Vec3& m, double eta);
// Snell's map at a flat interface, from a direction of polar cosine cos_from (> 0) in a medium of
// index 1 into one of relative index eta: |d omega_from / d omega_to| = eta^2 cos_to / cos_from
// (the etendue n^2 cos d omega is conserved). Zero on total internal reflection.
double FlatRefractionJacobian(double cos_from, double eta);
// Refracts `from` (pointing away from the facet m on the incident side) into a medium of relative
// index eta; returns the zero vector on total internal reflection.
Vec3 RefractThroughFacet(const Vec3& from, const Vec3& m, double eta);

struct SlabLobeParams {
  double eta = 1.5;
  double kappa_entry = kFlatConcentration;  // vMF concentration of the entry's normals
  double kappa_exit = kFlatConcentration;   // and of the exit's
};

class SlabLobeModel {
 public:
  // Throws svbtdf::common::Error(kInvalidInput) unless eta > 1 and both kappas are > 0.
  explicit SlabLobeModel(const SlabLobeParams& params);

  const SlabLobeParams& params() const { return params_; }

  // The chain of eq. 24 at the mean path for the viewer o: |d omega_m / d omega_i| for the exit's
  // normal (through the in-slab direction t) and for the entry's.
  struct Jacobians {
    double exit_to_slab = 0;   // |d omega_m_exit / d omega_t|
    double slab_to_light = 0;  // |d omega_t / d omega_i| (the flat Snell map out of the slab)
    double exit_to_light = 0;  // the product: |d omega_m_exit / d omega_i|
    double entry_to_light = 0; // |d omega_m_entry / d omega_i|
  };
  Jacobians MeanPathJacobians(const Vec3& o) const;

  // kappa_i of eq. 23 for the viewer o (o.z > 0); kFlatConcentration for a smooth slab.
  double LightConcentration(const Vec3& o) const;

  // The energy the lobe carries: the two interfaces' transmittances (1 - F) at the mean path,
  // times each rough interface's Smith masking of the mean path (the Beckmann G1 of the roughness
  // sqrt(2 / kappa) for the air-side and the in-slab direction, with m = z).
  double Energy(const Vec3& o) const;

  // rho(i, o) = Energy(o) M(-i; o, kappa_i(o)) / |i.z| for i.z < 0 < o.z, else 0: the lobe's
  // exit-direction density divided by the cosine, so that the integral of rho |i.z| over the light
  // hemisphere is Energy(o) times the lobe's mass below the horizon. Infinite concentration (a
  // smooth slab) has no density: Rho is then 0 (a delta).
  double Rho(const Vec3& i, const Vec3& o) const;

 private:
  SlabLobeParams params_;
};

}  // namespace svbtdf::model
