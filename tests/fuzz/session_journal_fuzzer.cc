// Fuzzes a session's journal.jsonl (docs/session-format.md) with the rest of the session valid.
#include "session_fuzzer.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  svbtdf::fuzz::InitializeSessionTarget("journal.jsonl");
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  svbtdf::fuzz::FuzzSessionFile(data, size);
  return 0;
}
