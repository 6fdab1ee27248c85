// Cooperative interruption (common/src/interrupt.cc): ThrowIfInterrupted throws an
// Error(kInterrupted) naming the work once an interrupt is requested, and not before; the
// installed handler turns SIGINT or SIGTERM into that request, and a second signal ends the
// process.
#include <gtest/gtest.h>

#include <csignal>
#include <string>

#include "svbtdf/common/error.h"
#include "svbtdf/common/interrupt.h"

namespace svbtdf::common {
namespace {

class Interrupt : public ::testing::Test {
 protected:
  void SetUp() override { SetInterruptRequested(false); }
  void TearDown() override {
    SetInterruptRequested(false);
    std::signal(SIGINT, SIG_DFL);
    std::signal(SIGTERM, SIG_DFL);
  }
};

TEST_F(Interrupt, NothingIsThrownUntilAnInterruptIsRequested) {
  EXPECT_FALSE(InterruptRequested());
  EXPECT_NO_THROW(ThrowIfInterrupted("fitting texels"));
  SetInterruptRequested(true);
  EXPECT_TRUE(InterruptRequested());
  try {
    ThrowIfInterrupted("fitting texels");
    FAIL() << "an interrupt was requested but nothing was thrown";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kInterrupted);
    EXPECT_EQ(ExitCodeFor(e.kind()), 130);
    EXPECT_EQ(e.subject(), "fitting texels");
    EXPECT_EQ(std::string(e.what()).rfind("fitting texels: interrupted", 0), 0u) << e.what();
    EXPECT_NE(e.hint().find("resume"), std::string::npos) << e.hint();
  }
  // The request stays until it is cleared: every later safe point stops too.
  EXPECT_THROW(ThrowIfInterrupted("writing the store"), Error);
}

TEST_F(Interrupt, ClearingTheRequestLetsWorkContinue) {
  SetInterruptRequested(true);
  EXPECT_THROW(ThrowIfInterrupted("a"), Error);
  SetInterruptRequested(false);
  EXPECT_FALSE(InterruptRequested());
  EXPECT_NO_THROW(ThrowIfInterrupted("a"));
}

TEST_F(Interrupt, SigintAndSigtermRequestAnInterruptOnceTheHandlerIsInstalled) {
  InstallInterruptHandler();
  ASSERT_FALSE(InterruptRequested());
  ASSERT_EQ(std::raise(SIGINT), 0);  // the handler runs before raise returns
  EXPECT_TRUE(InterruptRequested());
  EXPECT_THROW(ThrowIfInterrupted("capturing"), Error);
  SetInterruptRequested(false);
  ASSERT_EQ(std::raise(SIGTERM), 0);
  EXPECT_TRUE(InterruptRequested());
}

using InterruptDeathTest = Interrupt;

// A second Ctrl-C means "stop now": the default action, which ends the process by that signal.
TEST_F(InterruptDeathTest, ASecondSignalEndsTheProcess) {
  EXPECT_EXIT(
      {
        InstallInterruptHandler();
        std::raise(SIGINT);
        if (!InterruptRequested()) std::_Exit(3);  // the first one only sets the flag
        std::raise(SIGINT);
        std::_Exit(4);  // not reached
      },
      ::testing::KilledBySignal(SIGINT), "");
}

}  // namespace
}  // namespace svbtdf::common
