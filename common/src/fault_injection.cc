#include "svbtdf/common/fault_injection.h"

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "svbtdf/common/error.h"

namespace svbtdf::common {
namespace {

struct FaultPlan {
  int64_t at = 0;  // 0: no fault asked for
  FaultAction action = FaultAction::kProceed;
};

// Read once: the environment is the test's, fixed before the process starts.
FaultPlan ReadFaultPlan() {
  const char* text = std::getenv("SVBTDF_INJECT_FAULT");
  if (text == nullptr || *text == '\0') return {};
  const std::string spec(text);
  const size_t colon = spec.find(':');
  char* end = nullptr;
  const long long at = std::strtoll(spec.c_str(), &end, 10);
  const std::string action = colon == std::string::npos ? "" : spec.substr(colon + 1);
  if (end != spec.c_str() + colon || at < 1 || (action != "enospc" && action != "kill")) {
    // A test that misspells its fault must not silently run without it.
    std::fprintf(stderr, "svbtdf: SVBTDF_INJECT_FAULT='%s' is not N:enospc or N:kill\n", text);
    std::_Exit(2);
  }
  return {at, action == "kill" ? FaultAction::kKill : FaultAction::kFail};
}

std::atomic<int64_t> operations{0};
std::atomic<int64_t> fault_at{-1};  // -1: not read from the environment yet
std::atomic<FaultAction> fault_action{FaultAction::kProceed};

void ReadPlanOnce() {
  if (fault_at.load(std::memory_order_acquire) >= 0) return;
  static const bool read = [] {
    const FaultPlan plan = ReadFaultPlan();
    fault_action.store(plan.action);
    fault_at.store(plan.at, std::memory_order_release);
    return true;
  }();
  (void)read;
}

std::string HintFor(int error_number) {
  switch (error_number) {
    case ENOSPC:
    case EDQUOT:
      return "the disk is full: free some space, then run the same command again; nothing written so far is lost";
    case EROFS:
      return "the file system is read-only: choose a folder on a writable disk";
    case EACCES:
    case EPERM:
      return "permission denied: choose a folder you may write to, or change its permissions";
    case ELOOP:
      return "a symbolic link in the path points back at itself";
    case EIO:
      return "the disk reported an input/output error: check the disk and its cable";
    default:
      return {};
  }
}

}  // namespace

FaultAction NextDurableOperation() {
  ReadPlanOnce();
  const int64_t n = operations.fetch_add(1, std::memory_order_relaxed) + 1;
  return fault_at.load(std::memory_order_relaxed) == n ? fault_action.load() : FaultAction::kProceed;
}

void InjectFaultForTesting(int64_t at, FaultAction action) {
  ReadPlanOnce();
  fault_action.store(action);
  fault_at.store(at > 0 ? operations.load() + at : 0);
}

void FailOrKillIfInjected(const std::string& subject, const std::string& what) {
  switch (NextDurableOperation()) {
    case FaultAction::kProceed:
      return;
    case FaultAction::kFail:
      ThrowSystemError(subject, what, ENOSPC);
    case FaultAction::kKill:
      KillProcessNow();
  }
}

int64_t DurableOperationCount() { return operations.load(std::memory_order_relaxed); }

void KillProcessNow() {
  ::kill(::getpid(), SIGKILL);
  std::_Exit(137);  // not reached
}

void ThrowSystemError(const std::string& subject, const std::string& what, int error_number) {
  throw Error(ErrorKind::kIo, subject, what + ": " + std::strerror(error_number), HintFor(error_number));
}

}  // namespace svbtdf::common
