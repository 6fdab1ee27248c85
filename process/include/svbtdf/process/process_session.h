#pragma once
// From a calibrated capture session to the slice store (docs/slice-store.md; notes,
// "Measurement to BTDF"): for every dot, the bracketed images are dark-subtracted, linearised,
// rectified onto the texel grid and merged into HDR values, which the measurement equation turns
// into R(x, i_q, o); the slice store writer then separates the diffuse term and resamples.
//
// Images are read once, in plan order; memory is bounded by a few images and one dot's texel
// values, whatever the number of dots. An interrupted run resumes at the first unwritten dot.

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <vector>

#include "svbtdf/calib/session_calibration.h"
#include "svbtdf/session/session.h"

namespace svbtdf::process {

struct ProcessOptions {
  int texels_x = 0, texels_y = 0;  // 0: session.json rig.sample.texels_x/_y, else ~2 pixels per texel
  int light_resolution = 16;       // light hemicube of the resampled slices (power of two)
  int tile_texels = 1024;
  int rectify_samples = 3;         // k x k points per texel, inset from its edges, are averaged
  double diffuse_threshold = 0.05;
  int threads = 0;
  bool progress = true;
  // The monitor's measured emission profile (`--emission-profile PROFILE.json`, from `svbtdf
  // calibrate-emission`) instead of the calibration's nominal one; the store's copy of
  // calibration.json records the profile used.
  std::optional<calib::EmissionProfile> emission;
  // The monitor's polarisation (`--monitor-polarisation none|linear:DEG`) instead of the
  // session's rig.monitor.polarisation note. A linearly polarised screen's samples are divided by
  // the ratio of the slab's polarised to unpolarised transmittance (docs/capture.md, "A
  // polarised monitor"); "none" ignores a note.
  std::optional<std::string> polarisation;
};

struct ProcessReport {
  int64_t texels = 0, valid_texels = 0;
  int dots = 0, dots_resumed = 0;
  int64_t images_read = 0;
  double seconds = 0.0;
  bool already_complete = false;  // `out` held this processing, finished: nothing was done
  std::array<double, 3> white_exitance_noise = {0.0, 0.0, 0.0};  // the store's (WhiteExitanceNoise)
};

// The relative standard deviation, per channel, of each texel's white exitance L as measured
// from the flat white capture (one frame: its noise divides every sample of the texel alike, so
// no statistic over the dots sees it). Measured from the capture itself: the true L (the
// monitor's exitance times the camera's sensitivity and vignetting) is smooth from texel to
// texel and the noise is not, so d = ln L_t - (ln L_a + ln L_b) / 2 over the texels a, b on
// either side of t (along rows and along columns) has variance 1.5 sigma^2, and sigma is
// median |d| / 0.6745 / sqrt(1.5). `exitance` holds texels_x * texels_y * 3 values, NaN or not
// positive where unusable; a channel with fewer than 16 such triples gets 0 (not measured).
std::array<double, 3> WhiteExitanceNoise(const std::vector<float>& exitance, int texels_x, int texels_y);

// Writes the slice store into `out` (new, empty, or an unfinished processing of the same session
// to resume; a finished one of the same settings is reported already_complete and left alone). Throws svbtdf::Error naming the image or file for anything wrong with the input.
ProcessReport ProcessSession(const session::Session& session, const calib::SessionCalibration& calibration,
                             const std::filesystem::path& out, const ProcessOptions& options);

}  // namespace svbtdf::process
