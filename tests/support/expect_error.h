#pragma once
// Test support: run `body` and expect an svbtdf::Error of `kind` whose message contains `text`.

#include <gtest/gtest.h>

#include <string>

#include "svbtdf/common/error.h"

namespace svbtdf::testing {

template <typename Body>
void ExpectError(common::ErrorKind kind, const std::string& text, Body body) {
  try {
    body();
    FAIL() << "expected an error containing '" << text << "'";
  } catch (const common::Error& error) {
    EXPECT_EQ(error.kind(), kind) << error.what();
    EXPECT_NE(std::string(error.what()).find(text), std::string::npos) << error.what();
  }
}

}  // namespace svbtdf::testing
