#include "svbtdf/common/interrupt.h"

#include <atomic>
#include <csignal>

#include "svbtdf/common/error.h"

namespace svbtdf::common {
namespace {

std::atomic<bool> g_interrupt_requested{false};

extern "C" void HandleInterrupt(int signal_number) {
  if (g_interrupt_requested.exchange(true)) {
    // A second Ctrl-C means "stop now": restore the default action and re-raise.
    std::signal(signal_number, SIG_DFL);
    std::raise(signal_number);
  }
}

}  // namespace

void InstallInterruptHandler() {
  std::signal(SIGINT, HandleInterrupt);
  std::signal(SIGTERM, HandleInterrupt);
}

bool InterruptRequested() { return g_interrupt_requested.load(std::memory_order_relaxed); }

void SetInterruptRequested(bool requested) { g_interrupt_requested.store(requested); }

void ThrowIfInterrupted(const char* what) {
  if (InterruptRequested()) {
    throw Error(ErrorKind::kInterrupted, what, "interrupted",
                "progress so far is saved; run the same command again to resume");
  }
}

}  // namespace svbtdf::common
