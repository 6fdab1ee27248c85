#pragma once
// The monitor's angular emission profile P(theta_e): how the radiant intensity of a small patch of
// the screen falls off with the angle theta_e between the emitted direction and the screen's
// normal, relative to the normal direction (docs/calibration-format.md, "The emission profile").
//
//   isotropic   P = 1          the notes' point emitter, the paper's CRT assumption (the default)
//   lambertian  P = cos        a constant-radiance emitter
//   lcd         P = cos^n      a nominal LCD fall-off, n = exponent
//   measured    a table of P every step_deg from 0, measured with a diffuser session
//               (`svbtdf calibrate-emission`, calib/emission_fit.h); linear in ln P between nodes,
//               and beyond the table's last node cos^n with the measured exponent n
//
// Only the shape matters: the flat-field capture measures the monitor's exitance through the same
// profile, so a profile scaled by any constant gives the same BTDF. Measured tables are normalised
// to P(0) = 1.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace svbtdf::calib {

struct EmissionProfile {
  std::string kind = "isotropic";  // isotropic | lambertian | lcd | measured
  // lcd: P = cos^n. measured: the cos^n fit of the table, used beyond its last node.
  double exponent = 0.0;
  // measured: P at theta = k step_deg (k = 0 .. table.size() - 1), P(0) = 1, every value > 0.
  double step_deg = 0.0;
  std::vector<double> table;
  // measured: the angles the diffuser's dots reached with enough signal (informative; the
  // processing of a sample on the same rig sees the same angles).
  double covered_min_deg = 0.0, covered_max_deg = 0.0;

  // P for cos(theta_e); cos is clamped to [0, 1].
  double operator()(double cos_theta) const;
  // P for theta_e in degrees.
  double AtDegrees(double theta_deg) const;

  static EmissionProfile Isotropic() { return {}; }

  // Field by field; calibration.json keeps doubles to the last bit, so a profile read back
  // equals the one written.
  bool operator==(const EmissionProfile&) const = default;
};

// The profile as calibration.json's monitor keys hold it: `emission` (the kind),
// `emission_exponent` and, when measured, `emission_profile` {step_deg, table, covered_deg}.
void PutEmissionProfile(const EmissionProfile& profile, nlohmann::json* monitor);
// Reads those keys of `monitor` (an absent `emission` is isotropic). Throws
// svbtdf::Error(kFormat) naming `source` for an unknown kind or a value outside its physical
// range (exponent < 0 or > 50, step outside (0, 30] degrees, a table value not in (0, 10], a
// table not starting at 1, or reaching past 90 degrees).
EmissionProfile EmissionProfileFromJson(const nlohmann::json& monitor, const std::string& source);

// What `svbtdf calibrate-emission` measured besides the profile itself.
struct EmissionFitReport {
  int64_t observations = 0;      // (texel, dot) samples used
  int64_t texels = 0;            // texels they came from
  double residual_rms = 0.0;     // RMS of ln(measured / fitted), over the observations
  // Standard error of ln P at each node relative to the best-measured one (0 there): the
  // shape's uncertainty (the scale is free).
  std::vector<double> table_std;
  std::vector<int64_t> table_observations;  // observations within a step of each node
  double cos_power_residual_rms = 0.0;       // RMS of the best single cos^n's ln residual
};

// PROFILE.json, format "svbtdf-emission-profile", version 1: the profile (the keys of
// PutEmissionProfile), the fit's report and a free-form provenance.
inline constexpr int kEmissionProfileFormatVersion = 1;
void WriteEmissionProfileFile(const std::filesystem::path& path, const EmissionProfile& profile,
                              const EmissionFitReport& report, const nlohmann::json& provenance);
// Throws svbtdf::Error(kFormat) naming the file for anything malformed or out of range, and for
// a profile that is not `measured`.
EmissionProfile ReadEmissionProfileFile(const std::filesystem::path& path);

}  // namespace svbtdf::calib
