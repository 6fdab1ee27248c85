#pragma once
// Fitting the monitor's emission profile P(theta_e) to a diffuser session's measurements
// (docs/calibration-format.md, "The emission profile"). A near-Lambertian transmitting diffuser
// in the sample holder has a flat BTDF, so what processing measured under an isotropic
// assumption, R_iso(t, q), is c_t P(theta_tq): one unknown scale per texel (its rho_d, the flat
// field's own P at the camera's angle, any unevenness of the diffuser) times the profile at the
// angle at which dot q's light leaves the screen toward texel t.
//
// In logs this is linear: ln R_iso = a_t + ln P(theta). ln P is tabulated every step_deg and
// interpolated linearly; the per-texel offsets a_t are eliminated exactly (Schur complement), the
// scale is fixed by P(0) = 1, and a small second-difference penalty carries the table across
// angles no observation reaches. The normal equations' inverse gives each node's standard error,
// relative to the best-measured node (the shape's; the scale is free).

#include <cstdint>
#include <vector>

#include "svbtdf/calib/emission_profile.h"

namespace svbtdf::calib {

struct EmissionObservation {
  int64_t group = 0;       // observations of one group share an unknown scale (a texel)
  double theta_deg = 0.0;  // emission angle toward the texel, from the screen's normal
  double value = 0.0;      // R_iso (> 0; others are skipped)
  double weight = 1.0;     // relative inverse variance of ln(value)
};

struct EmissionFitOptions {
  double step_deg = 2.0;      // node spacing of the table (docs say why 2 degrees)
  // Second-difference penalty, in units of a node's mean data weight: enough to carry the table
  // across a node no sample reaches, too little to bend it where samples are (a larger one
  // biased the sparse end nodes of a cos^5 by 1-2.5%: ln cos^n is not straight).
  double smoothness = 1e-4;
  // A node is covered when at least this many observations lie within a step of it and its
  // standard error of ln P is below max_node_std.
  int64_t min_node_observations = 30;
  double max_node_std = 0.005;
};

struct EmissionFit {
  EmissionProfile profile;  // kind "measured", table up to the last covered node
  EmissionFitReport report;
};

// Throws svbtdf::Error(kInvalidInput) when fewer than two nodes are covered.
EmissionFit FitEmissionProfile(const std::vector<EmissionObservation>& observations,
                               const EmissionFitOptions& options = {});

}  // namespace svbtdf::calib
