#pragma once
// The pipeline from a capture session to a material, in its one order (`svbtdf run`): calibrate
// (or reuse SESSION/calibration.json), check the calibration, process into WORK/processed unless
// a finished store is there (an unfinished one resumes), check the store, fit and write the
// material, check it and record every stage's warnings in MATERIAL/quality.json
// (docs/quality.md). `svbtdf fit` is its last step alone (FitAndWriteMaterial).

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "svbtdf/calib/calibrate_session.h"
#include "svbtdf/fit/fit_material.h"
#include "svbtdf/fit/quality.h"
#include "svbtdf/process/process_session.h"

namespace svbtdf::process {

// What the pipeline tells its user as it goes: a line about a stage, and a stage's quality
// warnings as soon as the stage is checked. Either may be empty.
struct PipelineListener {
  std::function<void(const std::string& line)> say;
  std::function<void(const std::vector<fit::QualityWarning>& warnings)> warn;
};

// `svbtdf calibrate SESSION`: calibrates the session, writes SESSION/calibration.json and checks
// it (docs/quality.md). The command line and the Python module both run this.
struct CalibrationStage {
  calib::SessionCalibration calibration;
  std::filesystem::path file;                 // SESSION/calibration.json
  std::vector<fit::QualityWarning> warnings;  // the calibration's
};
CalibrationStage CalibrateAndCheck(const std::filesystem::path& session, const calib::CalibrateSessionOptions& options);

// `svbtdf process SESSION --out DIR`: a calibrated session into the slice store DIR (new, or an
// unfinished processing to resume), checked. Throws svbtdf::Error(kInvalidInput) naming SESSION
// when it has no calibration.json.
struct ProcessStage {
  ProcessReport report;
  std::vector<fit::QualityWarning> warnings;  // the store's
};
ProcessStage ProcessAndCheck(const std::filesystem::path& session, const std::filesystem::path& out,
                             const ProcessOptions& options);

// The checkpoint of an unfinished fit of MATERIAL, next to it (the material folder itself is
// written only once, complete).
std::filesystem::path FitCheckpointPath(const std::filesystem::path& material);

// Fits PROCESSED and writes the material to OUT (new or empty), resumably: finished fits are
// checkpointed next to OUT until the material is written. Then checks the material and writes
// OUT/quality.json with `earlier` (the calibration's and the processing's warnings) followed by the
// fit's; when `earlier` is null they are computed from PROCESSED (its calibration.json and maps)
// and reported too. Returns all of them. Throws svbtdf::Error(kInvalidInput) naming OUT when it
// exists and is not empty: a material is never overwritten.
std::vector<fit::QualityWarning> FitAndWriteMaterial(const std::filesystem::path& processed,
                                                     const std::filesystem::path& out, fit::FitMaterialOptions options,
                                                     const PipelineListener& listener,
                                                     const std::vector<fit::QualityWarning>* earlier = nullptr);

struct PipelineOptions {
  std::filesystem::path session, out;
  std::filesystem::path work;  // empty: OUT.work
  ProcessOptions process;
  fit::FitMaterialOptions fit;
};

struct PipelineOutcome {
  std::filesystem::path work;                 // where the processed slices are (reusable)
  std::vector<fit::QualityWarning> warnings;  // every stage's, as in OUT/quality.json
};

// Runs the whole pipeline. Throws svbtdf::Error naming the folder for an OUT that is not empty
// (checked first) or an incomplete session, and every stage's errors.
PipelineOutcome RunPipeline(const PipelineOptions& options, const PipelineListener& listener);

}  // namespace svbtdf::process
