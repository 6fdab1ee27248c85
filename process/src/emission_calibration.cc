#include "svbtdf/process/emission_calibration.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "svbtdf/calib/session_calibration.h"
#include "svbtdf/common/error.h"
#include "svbtdf/fit/slice_store.h"
#include "svbtdf/process/pipeline.h"
#include "svbtdf/session/session.h"

namespace svbtdf::process {
namespace fs = std::filesystem;
namespace {

// Samples whose image signal is below this fraction of the texel's brightest are left out: they
// are the faint corners where read noise and quantisation bias ln R.
constexpr double kMinRelativeSignal = 0.002;
// The weight of a sample, s / (s + kHalfWeightSignal) for its relative image signal s: bright
// samples count fully, faint ones (whose ln R is noisy) less.
constexpr double kHalfWeightSignal = 0.05;

}  // namespace

std::vector<calib::EmissionObservation> EmissionObservations(const fit::SliceStore& store) {
  const fit::TexelGeometry& g = store.geometry();
  const int dots = store.info().num_dots;
  std::vector<calib::EmissionObservation> out;
  std::vector<float> samples;
  std::vector<double> signal(dots);
  for (int64_t t = 0; t < g.num_texels(); ++t) {
    store.ReadSamples(t, &samples);
    const model::Vec3 x = g.TexelCentre(t);
    double brightest = 0;
    for (int q = 0; q < dots; ++q) {
      const double r = (samples[3 * q] + samples[3 * q + 1] + samples[3 * q + 2]) / 3.0;
      const model::Vec3 i = g.Light(t, q);
      // What the camera saw, up to the texel's constant: R |i.z| / |p - x|^2 (isotropic L_q).
      signal[q] = std::isfinite(r) && r > 0 ? r * std::abs(i.z()) / (g.dots[q] - x).squaredNorm() : 0.0;
      brightest = std::max(brightest, signal[q]);
    }
    if (!(brightest > 0)) continue;
    for (int q = 0; q < dots; ++q) {
      const double s = signal[q] / brightest;
      if (s < kMinRelativeSignal) continue;
      calib::EmissionObservation o;
      o.group = t;
      const double cos_e = std::clamp(-g.Light(t, q).dot(g.monitor_normal), -1.0, 1.0);
      o.theta_deg = std::acos(cos_e) * 180.0 / std::numbers::pi;
      o.value = (samples[3 * q] + samples[3 * q + 1] + samples[3 * q + 2]) / 3.0;
      o.weight = s / (s + kHalfWeightSignal);
      out.push_back(o);
    }
  }
  return out;
}

EmissionCalibration CalibrateEmission(const fs::path& session_folder, const fs::path& work,
                                      const EmissionCalibrationOptions& options) {
  const fs::path calibration_path = session_folder / "calibration.json";
  if (!fs::exists(calibration_path)) {
    calib::CalibrateSessionOptions calibrate;
    calibrate.progress = options.progress;
    CalibrateAndCheck(session_folder, calibrate);
  }
  const session::Session session = session::Session::Open(session_folder);
  const calib::SessionCalibration calibration = calib::ReadSessionCalibration(calibration_path);
  ProcessOptions process;
  process.texels_x = options.texels_x;
  process.texels_y = options.texels_y;
  process.threads = options.threads;
  process.progress = options.progress;
  // The diffuser is measured as if the screen were isotropic: what the fit sees is then the
  // profile itself, whatever the calibration says.
  process.emission = calib::EmissionProfile::Isotropic();
  EmissionCalibration result;
  result.processing = ProcessSession(session, calibration, work, process);
  const fit::SliceStore store = fit::SliceStore::Open(work);
  result.fit = calib::FitEmissionProfile(EmissionObservations(store), options.fit);
  result.provenance = {{"session", fs::absolute(session_folder).string()},
                       {"texels", {options.texels_x, options.texels_y}},
                       {"step_deg", options.fit.step_deg},
                       {"smoothness", options.fit.smoothness},
                       {"processed", fs::absolute(work).string()}};
  return result;
}

}  // namespace svbtdf::process
