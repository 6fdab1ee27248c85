#include "svbtdf/process/pipeline.h"

#include <cstdio>
#include <nlohmann/json.hpp>

#include "svbtdf/calib/calibrate_session.h"
#include "svbtdf/calib/emission_profile.h"
#include "svbtdf/calib/session_calibration.h"
#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/json.h"
#include "svbtdf/fit/material.h"
#include "svbtdf/fit/slice_store.h"
#include "svbtdf/fit/slice_store_format.h"
#include "svbtdf/process/calibration_quality.h"
#include "svbtdf/session/session.h"

namespace svbtdf::process {
namespace fs = std::filesystem;
namespace {

// printf into a std::string, for the listener's lines.
template <typename... Args>
std::string Format(const char* format, Args... args) {
  const int size = std::snprintf(nullptr, 0, format, args...);
  std::string text(static_cast<size_t>(std::max(size, 0)), '\0');
  std::snprintf(text.data(), text.size() + 1, format, args...);
  return text;
}

void Say(const PipelineListener& listener, const std::string& line) {
  if (listener.say) listener.say(line);
}

void Warn(const PipelineListener& listener, const std::vector<fit::QualityWarning>& warnings) {
  if (listener.warn && !warnings.empty()) listener.warn(warnings);
}

void RequireNewOrEmpty(const fs::path& out) {
  if (fs::exists(out) && (!fs::is_directory(out) || !fs::is_empty(out))) {
    common::ThrowInvalidInput(out.string(), "exists and is not empty; a material is never overwritten", "choose a new --out folder");
  }
}

void SayWhatWasFitted(const fit::Material& material, const fs::path& out, const PipelineListener& listener) {
  const nlohmann::json& statistics = material.provenance["statistics"];
  Say(listener, Format("fitted %s: %s representatives of %s valid texels (%s failed, %s resumed) in %.1f s "
                       "(clustering %.1f s, representatives %.1f s at %.2f s per fit, refinement %.1f s); "
                       "median residual %.3f",
                       fit::MaterialModelName(material.model), statistics["representatives"].dump().c_str(),
                       statistics["valid_texels"].dump().c_str(), statistics["failed_fits"].dump().c_str(),
                       statistics["resumed_fits"].dump().c_str(), statistics["seconds"].get<double>(),
                       statistics["clustering_seconds"].get<double>(), statistics["fit_seconds"].get<double>(),
                       statistics["seconds_per_fit"].get<double>(), statistics["refine_seconds"].get<double>(),
                       statistics["median_relative_rmse"].is_number() ? statistics["median_relative_rmse"].get<double>()
                                                                      : -1.0));
  if (statistics.value("horizon_fixed_instead", int64_t{0}) > 0) {
    Say(listener, Format("%s representatives fitted with the NDF's horizon fixed: the free horizon left their k_s "
                         "implausible (docs/fitting.md, \"Horizon\")",
                         statistics["horizon_fixed_instead"].dump().c_str()));
  }
  if (statistics["refined_representatives"].get<int64_t>() > 0) {
    Say(listener, "refined alpha and k_s of " + statistics["refined_representatives"].dump() + " representatives");
  }
  if (statistics["refined_texels"].get<int64_t>() > 0) {
    // A parametric lobe (ggx, slab) keeps its cluster's shape: only its scale is refitted.
    const char* refined = material.model == fit::MaterialModel::kDualMicrofacet ? "alpha, k_s and weights" : "k_s";
    Say(listener, Format("refined %s of %s interpolated texels: median residual %.3f -> %.3f", refined,
                         statistics["refined_texels"].dump().c_str(),
                         statistics["median_relative_rmse_blended"].get<double>(),
                         statistics["median_relative_rmse_refined"].get<double>()));
  }
  Say(listener, "material: " + out.string());
}

calib::SessionCalibration CalibrationOf(const session::Session& session, const PipelineListener& listener) {
  const fs::path path = session.folder() / "calibration.json";
  if (fs::exists(path)) {
    Say(listener, "== 1/3 calibration: using " + path.string());
    return calib::ReadSessionCalibration(path);
  }
  Say(listener, "== 1/3 calibrating " + session.folder().string());
  const calib::SessionCalibration calibration = calib::CalibrateSession(session);
  calib::WriteSessionCalibration(path, calibration);
  Say(listener, Format("camera fx %.1f fy %.1f, RMS %.3f px; sample plane RMS %.3f px; monitor %.2f mm behind, dots "
                       "RMS %.3f mm",
                       calibration.camera.camera.fx, calibration.camera.camera.fy, calibration.camera.rms_px,
                       calibration.sample_plane.rms_px, 1000 * calibration.monitor.distance_m,
                       calibration.monitor.residual_rms_mm));
  return calibration;
}

void ProcessUnlessDone(const session::Session& session, const calib::SessionCalibration& calibration,
                       const fs::path& processed, const ProcessOptions& options, const PipelineListener& listener) {
  std::string corrected;  // the polarisation a finished store was corrected for ("": none)
  try {
    corrected = common::StringOr(fit::SliceStore::Open(processed).info().provenance, "polarisation_corrected");
  } catch (const common::Error&) {
    // Not there or unfinished: process (an unfinished store resumes).
    Say(listener, "== 2/3 processing into " + processed.string());
    const ProcessReport report = ProcessSession(session, calibration, processed, options);
    Say(listener, Format("%d dots (%d resumed), %lld of %lld texels valid, %.1f s", report.dots, report.dots_resumed,
                         static_cast<long long>(report.valid_texels), static_cast<long long>(report.texels),
                         report.seconds));
    return;
  }
  // A finished store is reused, but never one processed under another emission profile than the
  // one asked for (a --work folder shared between runs with and without --emission-profile).
  const calib::EmissionProfile& wanted = options.emission ? *options.emission : calibration.monitor.emission;
  const fs::path store_calibration = processed / "calibration.json";
  if (calib::ReadSessionCalibration(store_calibration).monitor.emission != wanted) {
    common::ThrowInvalidInput(processed.string(),
                              "was processed under another monitor emission profile than the one asked for",
                              "give the same --emission-profile, or another --work folder");
  }
  // ... nor one corrected for another polarisation of the monitor.
  const std::string wanted_polarisation = options.polarisation ? *options.polarisation : session.rig().monitor.polarisation;
  const session::PolarisationNote note = session::ParsePolarisationNote(wanted_polarisation, "--monitor-polarisation");
  if (note.linear != !corrected.empty() ||
      (note.linear && session::ParsePolarisationNote(corrected, processed.string()).angle_deg != note.angle_deg)) {
    common::ThrowInvalidInput(processed.string(), "was processed for another monitor polarisation than the one asked for",
                              "give the same --monitor-polarisation, or another --work folder");
  }
  Say(listener, "== 2/3 processing: using " + processed.string());
}

}  // namespace

CalibrationStage CalibrateAndCheck(const fs::path& session_folder, const calib::CalibrateSessionOptions& options) {
  const session::Session session = session::Session::Open(session_folder);
  CalibrationStage stage;
  stage.calibration = calib::CalibrateSession(session, options);
  stage.file = session_folder / "calibration.json";
  calib::WriteSessionCalibration(stage.file, stage.calibration);
  stage.warnings = CheckCalibration(stage.calibration, stage.file.string());
  return stage;
}

ProcessStage ProcessAndCheck(const fs::path& session_folder, const fs::path& out, const ProcessOptions& options) {
  const session::Session session = session::Session::Open(session_folder);
  const fs::path calibration_path = session_folder / "calibration.json";
  if (!fs::exists(calibration_path)) {
    common::ThrowInvalidInput(session_folder.string(), "has no calibration.json",
                              "run 'svbtdf calibrate " + session_folder.string() + "' first");
  }
  const calib::SessionCalibration calibration = calib::ReadSessionCalibration(calibration_path);
  ProcessStage stage;
  stage.report = ProcessSession(session, calibration, out, options);
  stage.warnings = fit::CheckSliceStore(out);
  return stage;
}

fs::path FitCheckpointPath(const fs::path& material) {
  const fs::path folder = common::WithoutTrailingSeparators(material);
  return folder.parent_path() / (folder.filename().string() + ".partial-fits.jsonl");
}

std::vector<fit::QualityWarning> FitAndWriteMaterial(const fs::path& processed, const fs::path& out,
                                                     fit::FitMaterialOptions options, const PipelineListener& listener,
                                                     const std::vector<fit::QualityWarning>* earlier) {
  options.checkpoint = FitCheckpointPath(out);
  if (fs::exists(out / "material.json") && fs::exists(options.checkpoint)) {
    // A kill between the material's rename into place and the checkpoint's removal: the
    // material is whole, so its checkpoint is of no further use.
    fs::remove(options.checkpoint);
  }
  RequireNewOrEmpty(out);
  const fit::SliceStore store = fit::SliceStore::Open(processed);
  const fit::Material material = fit::FitMaterial(store, options);

  std::vector<fit::QualityWarning> warnings;
  if (earlier) {
    warnings = *earlier;
  } else {
    const fs::path calibration = processed / fit::store::kCalibration;
    warnings = CheckCalibration(calib::ReadSessionCalibration(calibration), calibration.string());
    const std::vector<fit::QualityWarning> stored = fit::CheckSliceStore(processed);
    warnings.insert(warnings.end(), stored.begin(), stored.end());
    Warn(listener, warnings);
  }
  const std::vector<fit::QualityWarning> fitted = fit::CheckMaterial(material, out);
  warnings.insert(warnings.end(), fitted.begin(), fitted.end());
  // The material appears whole or not at all: a kill or a full disk while it is written leaves
  // the checkpoint, from which the same command resumes, and no half material under its name.
  common::CreateFolderAtomically(out, [&](const fs::path& staging) {
    fit::WriteMaterial(staging, material);
    fit::WriteQuality(staging, warnings);
  });
  fs::remove(options.checkpoint);
  SayWhatWasFitted(material, out, listener);
  Warn(listener, fitted);
  return warnings;
}

PipelineOutcome RunPipeline(const PipelineOptions& options, const PipelineListener& listener) {
  RequireNewOrEmpty(options.out);
  PipelineOutcome outcome;
  outcome.work = options.work.empty() ? fs::path(common::WithoutTrailingSeparators(options.out).string() + ".work")
                                      : options.work;
  const session::Session session = session::Session::Open(options.session);
  const session::SessionVerification verification = session.Verify(/*check_crc=*/false);
  if (!verification.complete()) {
    common::ThrowInvalidInput(options.session.string(), "is not a complete session: " + verification.Summary(),
                      "finish the capture (re-run 'svbtdf acquire' with the same --out) or check it with 'svbtdf "
                      "session verify'");
  }
  // Every stage's output is checked after it (docs/quality.md), also when an earlier run made it.
  const calib::SessionCalibration calibration = CalibrationOf(session, listener);
  std::vector<fit::QualityWarning> warnings =
      CheckCalibration(calibration, (session.folder() / "calibration.json").string());
  Warn(listener, warnings);
  const fs::path processed = outcome.work / "processed";
  ProcessUnlessDone(session, calibration, processed, options.process, listener);
  const std::vector<fit::QualityWarning> stored = fit::CheckSliceStore(processed);
  Warn(listener, stored);
  warnings.insert(warnings.end(), stored.begin(), stored.end());
  Say(listener, "== 3/3 fitting");
  outcome.warnings = FitAndWriteMaterial(processed, options.out, options.fit, listener, &warnings);
  return outcome;
}

}  // namespace svbtdf::process
