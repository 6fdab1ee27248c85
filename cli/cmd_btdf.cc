#include "commands.h"

namespace svbtdf::cli {
void AddBtdfCommand(CLI::App& app) { (void)app; }
}  // namespace svbtdf::cli
