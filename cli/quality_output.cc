#include "quality_output.h"

#include <cstdio>

namespace svbtdf::cli {

void PrintQualityWarnings(const std::vector<fit::QualityWarning>& warnings) {
  std::fflush(stdout);  // keep the warnings after the lines of the stage they are about
  for (const fit::QualityWarning& warning : warnings) std::fprintf(stderr, "%s\n", warning.Line().c_str());
  std::fflush(stderr);
}

process::PipelineListener ConsoleListener() {
  return {[](const std::string& line) { std::printf("%s\n", line.c_str()); }, PrintQualityWarnings};
}

void AddStrictFlag(CLI::App* command, bool* strict) {
  command->add_flag("--strict", *strict,
                    "exit with code " + std::to_string(fit::kQualityWarningExitCode) +
                        " when the output draws quality warnings (docs/quality.md); the outputs are still written");
}

void ExitIfStrict(const std::vector<fit::QualityWarning>& warnings, bool strict) {
  if (!strict || warnings.empty()) return;
  std::fprintf(stderr, "svbtdf: %zu quality warning%s and --strict: exit code %d\n", warnings.size(),
               warnings.size() == 1 ? "" : "s", fit::kQualityWarningExitCode);
  throw CLI::RuntimeError(fit::kQualityWarningExitCode);
}

}  // namespace svbtdf::cli
