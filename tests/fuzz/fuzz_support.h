#pragma once
// What every fuzz target of tests/fuzz shares (docs/testing.md, "Fuzzing the readers").
//
// A target hands one input to one reader of a file a user hands in. The reader may refuse it with
// svbtdf::common::Error, the one error a user sees, as a line naming the file: that is the
// expected outcome for almost every input. Anything else is a finding: another exception escaping
// (the command line would print "internal error" naming nothing), a crash, a sanitizer report, a
// hang or an allocation beyond libFuzzer's limit.
//
// The same sources build two ways: against libFuzzer (SVBTDF_FUZZ, scripts/sanitize.sh), and
// against replay_main.cc, which runs the seed corpus in every build as a regression test.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>

#include "svbtdf/common/error.h"

namespace svbtdf::fuzz {

// This process's scratch folder, made on first use and removed at exit. It is in /dev/shm where
// there is one: every input is written to a file, and a RAM disk keeps that cheap.
// SVBTDF_FUZZ_SCRATCH=DIR uses DIR instead and keeps it, to look at what an input did.
const std::filesystem::path& ScratchFolder();

// Replaces `path` with the input's bytes. A plain write: scratch files need no durability.
void WriteInput(const std::filesystem::path& path, const uint8_t* data, size_t size);

// Copies the committed fixture tests/fuzz/fixtures/NAME into the scratch folder; returns the copy.
std::filesystem::path CopyFixture(const std::string& name);

// A fixture the harness made (or copied) and must be able to read: when it cannot, the harness is
// out of date with the format, which is not a finding about the reader. Prints why and exits 1.
[[noreturn]] void FixtureBroken(const std::string& what);

// Runs `read`; a refusal with svbtdf::common::Error is the expected outcome, anything else escapes.
template <class Read>
void ExpectOnlySvbtdfErrors(Read&& read) {
  try {
    read();
  } catch (const common::Error&) {
  }
}

// Writes the input to ScratchFolder()/`file_name` and reads it with `read(path)`, expecting only
// svbtdf errors: the whole of a target whose reader takes one file.
void FuzzFile(const char* file_name, const uint8_t* data, size_t size,
              const std::function<void(const std::filesystem::path&)>& read);

// Runs `read` on a fixture that must be read without error (see FixtureBroken).
template <class Read>
void RequireFixtureReads(const std::string& fixture, Read&& read) {
  try {
    read();
  } catch (const common::Error& error) {
    FixtureBroken(fixture + ": " + error.what());
  }
}

}  // namespace svbtdf::fuzz
