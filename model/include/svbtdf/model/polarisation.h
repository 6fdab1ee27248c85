#pragma once
// Linearly polarised light through smooth dielectric interfaces (docs/model.md, "Polarised
// light"). An LCD emits linearly polarised light, and an interface transmits its s and p parts
// (electric field perpendicular to / in the plane of incidence) differently. The model's
// virtual configurations each send the light through two interfaces (one a microfacet, one the
// flat side), so for a polarised source their Fresnel product (1 - F_1)(1 - F_2) becomes the
// power left after two such transmissions.
//
// The field is carried as a real vector transverse to the travel direction (a Jones vector in
// the world frame), its squared length the beam's power. At each interface it is split into s
// and p, each scaled by the square root of its power transmittance, and the p part turned with
// the ray (p = s x travel before and after). Transmission amplitudes of a dielectric are real
// and positive (no total internal reflection on a transmitted path), so a linearly polarised
// beam stays linearly polarised and this is exact (no approximation beyond smooth facets):
// the Mueller calculus gives the same powers (tests/model/polarisation_test.cc checks it with an
// independent Stokes computation). Unpolarised light is the incoherent mean of any two
// orthogonal linear states. The s and p reflectances of one interface are fresnel.h's
// (FresnelDielectricSP).

#include "svbtdf/model/vec.h"

namespace svbtdf::model {

// A beam after a smooth interface: where it travels and its field (squared length = power).
struct TransmittedBeam {
  bool valid = false;  // false under total internal reflection (nothing is transmitted)
  Vec3 travel = Vec3::UnitZ();
  Vec3 field = Vec3::Zero();
};

// Refracts a beam travelling along unit `travel` with transverse field `field` through a smooth
// interface with unit `normal` (either orientation), eta = n_beyond / n_before.
TransmittedBeam TransmitPolarised(const Vec3& travel, const Vec3& field, const Vec3& normal, double eta);

// The unit field of linearly polarised light travelling along `travel` whose source field lies
// along `source_field` (the monitor's polarisation direction, a fixed world vector): its part
// transverse to the ray, normalised. Zero when the ray runs along `source_field`.
Vec3 TransverseField(const Vec3& source_field, const Vec3& travel);

// Power transmitted through two smooth interfaces in turn by a unit-power beam along `travel`
// (air side) with unit transverse field `field`: normal1 with eta1, then normal2 with eta2
// (each eta = n_beyond / n_before). 0 under total internal reflection at either. For a slab
// with air on both sides, eta2 = 1 / eta1.
double TwoInterfaceTransmittance(const Vec3& travel, const Vec3& field, const Vec3& normal1, double eta1,
                                 const Vec3& normal2, double eta2);

// The same for unpolarised light: the mean over two orthogonal linear states (exact).
double TwoInterfaceTransmittanceUnpolarised(const Vec3& travel, const Vec3& normal1, double eta1,
                                            const Vec3& normal2, double eta2);

}  // namespace svbtdf::model
