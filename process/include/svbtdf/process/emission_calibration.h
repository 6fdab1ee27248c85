#pragma once
// `svbtdf calibrate-emission DIFFUSER_SESSION --out PROFILE.json`: the monitor's angular emission
// profile measured with a near-Lambertian transmitting diffuser (opal glass) in the sample holder
// (docs/capture.md, "Measuring the monitor's emission"; docs/calibration-format.md, "The
// emission profile"). The diffuser session is calibrated (SESSION/calibration.json, made first
// when missing) and processed with an isotropic profile on a coarse texel grid, so that each
// texel averages many pixels; every (texel, dot) sample then says how bright the screen is toward
// that texel at that dot's emission angle, and calib::FitEmissionProfile fits the profile.

#include <filesystem>
#include <vector>

#include <nlohmann/json.hpp>

#include "svbtdf/calib/emission_fit.h"
#include "svbtdf/fit/slice_store.h"
#include "svbtdf/process/process_session.h"

namespace svbtdf::process {

struct EmissionCalibrationOptions {
  int texels_x = 16, texels_y = 16;  // the diffuser's processing grid
  calib::EmissionFitOptions fit;
  int threads = 0;
  bool progress = true;
};

struct EmissionCalibration {
  calib::EmissionFit fit;
  ProcessReport processing;
  nlohmann::json provenance;  // the session, the grid and the fit's settings (PROFILE.json's)
};

// Processes `session` into `work` (new, or an unfinished or finished processing of the same
// settings: resumed or reused) and fits the profile. Throws svbtdf::Error naming the session or
// file for anything wrong with the input, and kInvalidInput when the dots cover too few angles.
EmissionCalibration CalibrateEmission(const std::filesystem::path& session, const std::filesystem::path& work,
                                      const EmissionCalibrationOptions& options);

// The observations of a processed diffuser: per texel with valid samples, every dot's mean R over
// the channels at its emission angle, weighted by how far it stands above the noise.
std::vector<calib::EmissionObservation> EmissionObservations(const fit::SliceStore& store);

}  // namespace svbtdf::process
