#include "commands.h"

namespace svbtdf::cli {

void AddAllCommands(CLI::App& app) {
  AddBtdfCommand(app);
  AddCalibrateCommand(app);
}

}  // namespace svbtdf::cli
