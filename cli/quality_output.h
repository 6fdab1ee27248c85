#pragma once
// The quality warnings of the pipeline's commands on the command line (docs/quality.md):
// printed to stderr one line each, and, with --strict, turned into exit code 4 (fit::kQualityWarningExitCode).

#include <CLI/CLI.hpp>

#include <vector>

#include "svbtdf/fit/quality.h"
#include "svbtdf/process/pipeline.h"

namespace svbtdf::cli {

// Prints each warning's line ("warning: STAGE: FILE: ...") on stderr.
void PrintQualityWarnings(const std::vector<fit::QualityWarning>& warnings);
// The pipeline's lines on stdout and its warnings on stderr, as they come.
process::PipelineListener ConsoleListener();
// Declares --strict on `command`.
void AddStrictFlag(CLI::App* command, bool* strict);
// With `strict` and at least one warning: says so on stderr and throws CLI::RuntimeError with
// fit::kQualityWarningExitCode (main.cc returns it). Otherwise does nothing.
void ExitIfStrict(const std::vector<fit::QualityWarning>& warnings, bool strict);

}  // namespace svbtdf::cli
