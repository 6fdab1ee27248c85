// The error convention (common/src/error.cc): the one-line message, the shorthands' kinds and
// the exit code of each kind.
#include <gtest/gtest.h>

#include <string>

#include "svbtdf/common/error.h"

namespace svbtdf::common {
namespace {

TEST(Error, MessageNamesSubjectProblemAndHint) {
  const Error error(ErrorKind::kInvalidInput, "--eta", "must be greater than 1", "got 0.9");
  EXPECT_STREQ(error.what(), "--eta: must be greater than 1 (got 0.9)");
  EXPECT_EQ(error.subject(), "--eta");
  EXPECT_EQ(error.problem(), "must be greater than 1");
  EXPECT_EQ(error.hint(), "got 0.9");
  EXPECT_EQ(ExitCodeFor(error.kind()), 2);
  EXPECT_EQ(ExitCodeFor(ErrorKind::kIo), 1);
  EXPECT_EQ(ExitCodeFor(ErrorKind::kInterrupted), 130);
}

TEST(Error, MessageLeavesOutAnEmptySubjectOrHint) {
  EXPECT_STREQ(Error(ErrorKind::kIo, "a.json", "cannot be read").what(), "a.json: cannot be read");
  EXPECT_STREQ(Error(ErrorKind::kNumerical, "", "did not converge", "try more iterations").what(),
               "did not converge (try more iterations)");
  EXPECT_STREQ(Error(ErrorKind::kHardware, "", "camera gone").what(), "camera gone");
}

TEST(Error, EveryKindHasItsExitCode) {
  EXPECT_EQ(ExitCodeFor(ErrorKind::kInvalidInput), 2);
  EXPECT_EQ(ExitCodeFor(ErrorKind::kFormat), 2);
  EXPECT_EQ(ExitCodeFor(ErrorKind::kIo), 1);
  EXPECT_EQ(ExitCodeFor(ErrorKind::kHardware), 1);
  EXPECT_EQ(ExitCodeFor(ErrorKind::kNumerical), 1);
  EXPECT_EQ(ExitCodeFor(ErrorKind::kInterrupted), 130);
}

// The shorthands throw an Error of their kind carrying the three parts.
template <typename Thrower>
Error Caught(Thrower thrower) {
  try {
    thrower();
  } catch (const Error& e) {
    return e;
  }
  ADD_FAILURE() << "nothing was thrown";
  return Error(ErrorKind::kHardware, "", "");
}

TEST(Error, ShorthandsThrowTheirKind) {
  const Error invalid = Caught([] { ThrowInvalidInput("--threads", "must be positive", "got -1"); });
  EXPECT_EQ(invalid.kind(), ErrorKind::kInvalidInput);
  EXPECT_STREQ(invalid.what(), "--threads: must be positive (got -1)");
  const Error format = Caught([] { ThrowFormatError("m.json", "version 99 is not supported"); });
  EXPECT_EQ(format.kind(), ErrorKind::kFormat);
  EXPECT_EQ(format.subject(), "m.json");
  EXPECT_EQ(format.hint(), "");
  const Error io = Caught([] { ThrowIoError("/out", "disk full", "free some space"); });
  EXPECT_EQ(io.kind(), ErrorKind::kIo);
  EXPECT_EQ(io.problem(), "disk full");
  EXPECT_EQ(io.hint(), "free some space");
}

}  // namespace
}  // namespace svbtdf::common
