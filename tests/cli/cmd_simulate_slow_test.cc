// `svbtdf simulate --preset demo` (the preset of the README's first command, 1,176 images, about
// 2.5 minutes on 2 cores): a complete session and its truth. In the slow suite (ctest -L slow).
#include <gtest/gtest.h>

#include <filesystem>

#include "run_command.h"
#include "svbtdf/session/session.h"
#include "temp_folder.h"

namespace svbtdf {
namespace {
namespace fs = std::filesystem;

TEST(SimulateCommandSlow, DemoPresetRunsToACompleteSession) {
  testing::TempFolder folder;
  const fs::path out = folder.path() / "demo";
  const auto result = testing::RunSvbtdf("-q simulate --preset demo --out " + out.string());
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const session::SessionVerification verification = session::Session::Open(out / "session").Verify(/*check_crc=*/true);
  EXPECT_TRUE(verification.complete()) << verification.Summary();
  EXPECT_EQ(session::Session::Open(out / "session").entries().size(), 1176u);
  for (const char* file : {"rig.json", "material.json", "alpha.exr"}) {
    EXPECT_TRUE(fs::exists(out / "truth" / file)) << file;
  }
}

}  // namespace
}  // namespace svbtdf
