#include "session_fuzzer.h"

#include "fuzz_support.h"
#include "svbtdf/session/session.h"

namespace svbtdf::fuzz {
namespace {

std::filesystem::path session_folder;
std::filesystem::path fuzzed_file;

void OpenAndVerify() {
  const session::Session session = session::Session::Open(session_folder);
  // No CRCs: the fixture has no images, so every entry is "corrupt"; what matters is that the
  // journal's entries, as read, are safe to check against the folder.
  (void)session.Verify(/*check_crc=*/false);
  (void)session.PlannedKeys(session::CaptureKind::kDot);
}

}  // namespace

void InitializeSessionTarget(const std::string& file) {
  session_folder = CopyFixture("session");
  fuzzed_file = session_folder / file;
  RequireFixtureReads(session_folder.string(), OpenAndVerify);
}

void FuzzSessionFile(const uint8_t* data, size_t size) {
  WriteInput(fuzzed_file, data, size);
  ExpectOnlySvbtdfErrors(OpenAndVerify);
}

}  // namespace svbtdf::fuzz
