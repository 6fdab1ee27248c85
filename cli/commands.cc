#include "commands.h"

#include <cstdio>

#include "svbtdf/common/error.h"

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

GridSize ParseGridSize(const std::string& text, const std::string& option, int largest) {
  GridSize size;
  char x = 0, extra = 0;
  if (std::sscanf(text.c_str(), "%d%c%d%c", &size.cols, &x, &size.rows, &extra) != 3 || x != 'x' || size.cols < 1 ||
      size.rows < 1 || size.cols > largest || size.rows > largest) {
    common::ThrowInvalidInput(option, "must be COLSxROWS with numbers from 1 to " + std::to_string(largest) + ", got '" +
                                          text + "'");
  }
  return size;
}

}  // namespace svbtdf::cli
