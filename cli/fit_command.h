#pragma once
// The fitting step of `svbtdf fit`, shared with `svbtdf run` (cmd_fit.cc).

#include <CLI/CLI.hpp>

#include <filesystem>
#include <string>
#include <vector>

#include "svbtdf/fit/fit_material.h"
#include "svbtdf/fit/quality.h"

namespace svbtdf::cli {

// Declares the fit's options (--eta, --representatives, --holdout, ...) on `command`.
void AddFitOptions(CLI::App* command, fit::FitMaterialOptions* options, std::string* representatives);
// "all" or a fraction in (0, 1]; svbtdf::Error naming --representatives otherwise.
double ParseRepresentatives(const std::string& text);
// Fits PROCESSED and writes the material to OUT (new or empty), resumably: finished fits are
// checkpointed next to OUT until the material is written. Then checks the material
// (docs/quality.md), prints its warnings and writes OUT/quality.json with `earlier` (the
// calibration's and the processing's warnings) followed by the fit's; when `earlier` is null they
// are computed from PROCESSED (its calibration.json and maps) and printed too. Returns all of them.
std::vector<fit::QualityWarning> FitAndWriteMaterial(const std::filesystem::path& processed,
                                                     const std::filesystem::path& out, fit::FitMaterialOptions options,
                                                     const std::vector<fit::QualityWarning>* earlier = nullptr);

}  // namespace svbtdf::cli
