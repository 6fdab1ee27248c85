#pragma once
// The three files of a capture session (session.json, plan.json, journal.jsonl), each fuzzed on
// its own inside an otherwise valid session: a committed fixture, tiny's session without images.

#include <cstddef>
#include <cstdint>
#include <string>

namespace svbtdf::fuzz {

// Copies the fixture once, then writes each input over `file` and opens and verifies the session.
void InitializeSessionTarget(const std::string& file);
void FuzzSessionFile(const uint8_t* data, size_t size);

}  // namespace svbtdf::fuzz
