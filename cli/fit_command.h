#pragma once
// The fitting step of `svbtdf fit`, shared with `svbtdf run` (cmd_fit.cc).

#include <CLI/CLI.hpp>

#include <filesystem>
#include <string>

#include "svbtdf/fit/fit_material.h"

namespace svbtdf::cli {

// Declares the fit's options (--eta, --representatives, --holdout, ...) on `command`.
void AddFitOptions(CLI::App* command, fit::FitMaterialOptions* options, std::string* representatives);
// "all" or a fraction in (0, 1]; svbtdf::Error naming --representatives otherwise.
double ParseRepresentatives(const std::string& text);
// Fits PROCESSED and writes the material to OUT (new or empty), resumably: finished fits are
// checkpointed next to OUT until the material is written.
void FitAndWriteMaterial(const std::filesystem::path& processed, const std::filesystem::path& out,
                         fit::FitMaterialOptions options);

}  // namespace svbtdf::cli
