#include "commands.h"

namespace svbtdf::cli {

void AddAllCommands(CLI::App& app) {
  AddAcquireCommand(app);
  AddBtdfCommand(app);
  AddCalibrateCommand(app);
  AddCalibrateEmissionCommand(app);
  AddCompareCommand(app);
  AddDevicesCommand(app);
  AddEvalCommand(app);
  AddExportCommand(app);
  AddFitCommand(app);
  AddPlanCommand(app);
  AddProcessCommand(app);
  AddRenderCommand(app);
  AddReportCommand(app);
  AddRunCommand(app);
  AddSessionCommand(app);
  AddSimulateCommand(app);
  AddValidateModelCommand(app);
}

}  // namespace svbtdf::cli
