#include "commands.h"

namespace svbtdf::cli {

void AddAllCommands(CLI::App& app) {
  AddBtdfCommand(app);
  AddCalibrateCommand(app);
  AddCompareCommand(app);
  AddDevicesCommand(app);
  AddEvalCommand(app);
  AddFitCommand(app);
  AddProcessCommand(app);
  AddReportCommand(app);
  AddSessionCommand(app);
  AddSimulateCommand(app);
  AddValidateModelCommand(app);
}

}  // namespace svbtdf::cli
