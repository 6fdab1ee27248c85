#pragma once
// Cooperative interruption: the command line installs a SIGINT/SIGTERM handler that sets a
// flag; long loops poll it at safe points, save what they have, and throw
// Error(kInterrupted) so that a rerun can resume.

namespace svbtdf::common {

void InstallInterruptHandler();
bool InterruptRequested();
// Throws Error(ErrorKind::kInterrupted) when an interrupt was requested; `what` names the work.
void ThrowIfInterrupted(const char* what);
// For tests: request or clear an interrupt without a signal.
void SetInterruptRequested(bool requested);

}  // namespace svbtdf::common
