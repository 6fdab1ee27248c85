#pragma once
// The fit's options of `svbtdf fit`, shared with `svbtdf run` (cmd_fit.cc).

#include <CLI/CLI.hpp>

#include <string>

#include "svbtdf/fit/fit_material.h"

namespace svbtdf::cli {

// Declares the fit's options (--eta, --representatives, --holdout, ...) on `command`.
void AddFitOptions(CLI::App* command, fit::FitMaterialOptions* options, std::string* representatives);
}  // namespace svbtdf::cli
