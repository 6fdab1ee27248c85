#pragma once
// A seam for testing durability without a full disk or a well-timed kill. Every operation that
// puts a user's data on disk (a write, an fsync, a truncation, a rename of a file the house keeps,
// a journal append) first asks NextDurableOperation(). Normally it answers kProceed and costs one
// relaxed atomic increment.
//
// With SVBTDF_INJECT_FAULT=N:enospc in the environment, the N-th such operation of the process
// (counting from 1) answers kFail and its caller fails as if the disk were full (errno ENOSPC);
// with SVBTDF_INJECT_FAULT=N:kill it answers kKill: the caller leaves what a crash at that instant
// would leave (a write cut in half) and calls KillProcessNow(). The tests walk N over every such
// operation of a command and check that a resumed run ends where an uninterrupted one does
// (docs/capture.md, "Durability").

#include <cstdint>
#include <string>

namespace svbtdf::common {

enum class FaultAction { kProceed, kFail, kKill };

// Counts this durable operation and says whether a test asked it to fail.
FaultAction NextDurableOperation();

// Counts this durable operation; when a test asked it to fail, throws ThrowSystemError(subject,
// what, ENOSPC), and when asked to kill, kills the process here. For operations that leave
// nothing partial behind (fsync, rename, truncate); a write cuts itself in half first.
void FailOrKillIfInjected(const std::string& subject, const std::string& what);

// Durable operations counted so far in this process.
int64_t DurableOperationCount();

// For tests in this process: from now on the `at`-th durable operation (counting from the next
// one as 1) gets `action`; at = 0 turns injection off. Overrides SVBTDF_INJECT_FAULT.
void InjectFaultForTesting(int64_t at, FaultAction action);

// SIGKILL to this process: what a crash or a pulled plug would do, no destructors, no flushing.
[[noreturn]] void KillProcessNow();

// Throws Error(kIo) naming `subject` with the system's words for `error_number` and, for the
// errors a user can act on (a full disk, a read-only or forbidden folder, a symbolic link loop),
// what to do about it. `what` says which operation failed ("cannot write", "fsync failed").
[[noreturn]] void ThrowSystemError(const std::string& subject, const std::string& what, int error_number);

}  // namespace svbtdf::common
