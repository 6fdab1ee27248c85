#pragma once
// Registration of the svbtdf subcommands. Each Add*Command() declares its options on `app`
// and attaches a callback that does the work and throws svbtdf::Error on failure.
// To add a command: write cmd_<name>.cc, declare its Add function here, list it in
// AddAllCommands (commands.cc) and in CMakeLists.txt.

#include <CLI/CLI.hpp>
#include <string>

namespace svbtdf::cli {

void AddAllCommands(CLI::App& app);

void AddAcquireCommand(CLI::App& app);        // svbtdf acquire
void AddBtdfCommand(CLI::App& app);           // svbtdf btdf eval
void AddCalibrateCommand(CLI::App& app);      // svbtdf calibrate
void AddCalibrateEmissionCommand(CLI::App& app);  // svbtdf calibrate-emission
void AddCompareCommand(CLI::App& app);        // svbtdf compare
void AddDevicesCommand(CLI::App& app);         // svbtdf devices
void AddEvalCommand(CLI::App& app);            // svbtdf eval
void AddExportCommand(CLI::App& app);          // svbtdf export
void AddFitCommand(CLI::App& app);             // svbtdf fit
void AddPlanCommand(CLI::App& app);            // svbtdf plan
void AddProcessCommand(CLI::App& app);         // svbtdf process
void AddRenderCommand(CLI::App& app);          // svbtdf render
void AddReportCommand(CLI::App& app);          // svbtdf report
void AddRunCommand(CLI::App& app);             // svbtdf run
void AddSessionCommand(CLI::App& app);         // svbtdf session verify
void AddSimulateCommand(CLI::App& app);        // svbtdf simulate
void AddValidateModelCommand(CLI::App& app);  // svbtdf validate-model

// A grid size given as COLSxROWS (`--texels 600x600`, `--dots 20x20`): each from 1 to `largest`.
// Throws svbtdf::Error(kInvalidInput) naming `option` otherwise.
struct GridSize {
  int cols = 0, rows = 0;
};
GridSize ParseGridSize(const std::string& text, const std::string& option, int largest);

}  // namespace svbtdf::cli
