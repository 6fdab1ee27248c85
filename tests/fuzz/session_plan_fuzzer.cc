// Fuzzes a session's plan.json (docs/session-format.md) with the rest of the session valid.
#include "session_fuzzer.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  svbtdf::fuzz::InitializeSessionTarget("plan.json");
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  svbtdf::fuzz::FuzzSessionFile(data, size);
  return 0;
}
