// The fitting half of the chain through the command line, on simulated sessions calibrated with
// their true rig (tests/calib checks `svbtdf calibrate` itself): `svbtdf process`, `svbtdf fit
// --holdout`, `svbtdf compare` (issue 5's acceptance), and resuming an interrupted fit.
#include <gtest/gtest.h>
#include <unistd.h>

#include <signal.h>
#include <sys/wait.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "run_command.h"
#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/image_io.h"
#include "fit_chain.h"

namespace svbtdf {
namespace {

// The `small` preset (20x20 dots, 32x32 texels) is the smallest whose lobes are sampled densely
// enough to judge the fit; 5% representatives (51) keep the default run short.
TEST_F(FitChain, RecoversTheTruthOnHeldOutDots) {
  const nlohmann::json m = FitAndCompare("material", "--holdout 0.1 --representatives 0.05");
  EXPECT_TRUE(m["holdout_recorded"].get<bool>());
  EXPECT_EQ(m["heldout_dots"].get<int>(), 40);
  EXPECT_GE(m["alpha_within_0_05"].get<double>(), 0.9);
  EXPECT_LT(m["ndf_rel_l2_median"].get<double>(), 0.10);
  EXPECT_LT(m["heldout_rel_rmse"].get<double>(), 0.05);
  EXPECT_LT(m["rho_d_rel_error_median"].get<double>(), 0.02);
  // Per-texel uncertainty (docs/validation.md, "Per-texel uncertainty"): how often the truth lies
  // within 2 standard errors. Measured on seeds 1-3 of this fit (own calibration, 2026-12-06):
  // alpha 86-92%, k_s 97-99%, rho_d 97-98% (88-91% before the flat white's noise was counted,
  // 2026-12-07), shadowing 94-97% (64-73% before its profile over D), NDF width 97-98%, rank
  // correlation of the predicted and the actual held-out error 0.38-0.57; this test's session
  // (its true calibration) measured alpha 83.4%, k_s 98.2%, rho_d 95.5% (83.4% before),
  // shadowing 97.7% (77.3% before its profile), NDF width 94.7%, rank correlation 0.37.
  // The target is 90-98%; the floors below hold what is reached, so that a change that
  // makes them worse, or inflates them into decoration (coverage near 100%), fails.
  const nlohmann::json& coverage = m["coverage_2se"];
  const std::pair<const char*, double> floors[] = {
      {"alpha", 0.75}, {"k_s", 0.90}, {"rho_d", 0.90}, {"shadowing_roughness", 0.90}, {"ndf_width", 0.85}};
  for (const auto& [parameter, floor] : floors) {
    ASSERT_TRUE(coverage[parameter].is_number()) << parameter;
    EXPECT_GE(coverage[parameter].get<double>(), floor) << parameter;
    EXPECT_LE(coverage[parameter].get<double>(), 0.99) << parameter;
  }
  EXPECT_GE(m["heldout_rank_correlation"].get<double>(), 0.35);
}

// The paper's 1% (10 representatives here): the interpolated texels, refined against their own
// samples, meet the held-out bound (measured 1.18%, alpha within 0.05 on 98.8%, NDF 2.5%).
// Fitting every texel measures 2.66% (cmd_run_slow_test.cc, which checks the 1.2x
// against it); 2.5% here keeps that bound in the default run too.
TEST_F(FitChain, OnePercentRepresentativesMeetTheHeldOutBound) {
  const nlohmann::json m = FitAndCompare("one_percent", "--holdout 0.1 --representatives 0.01");
  EXPECT_GE(m["alpha_within_0_05"].get<double>(), 0.9);
  EXPECT_LT(m["ndf_rel_l2_median"].get<double>(), 0.10);
  EXPECT_LT(m["heldout_rel_rmse"].get<double>(), 0.025);
}

TEST_F(FitChain, AnInterruptedFitResumesFromItsCheckpoint) {
  const fs::path out = root_ / "resumed";
  // A checkpoint from another fit is refused, never mixed in.
  common::WriteTextAtomically(root_ / "resumed.partial-fits.jsonl", "{\"fit\":{\"store\":\"elsewhere\"}}\n");
  auto refused = RunSvbtdf("fit " + Processed() + " --out " + out.string() + " --representatives 0.02");
  EXPECT_EQ(refused.exit_code, 2) << refused.output;
  EXPECT_NE(refused.output.find("checkpoint"), std::string::npos) << refused.output;
  fs::remove(root_ / "resumed.partial-fits.jsonl");
  // Stop the fit with SIGINT once a few fits are checkpointed, then run it again.
  const std::string command = std::string(SVBTDF_CLI_PATH) + " fit " + Processed() + " --out " + out.string() +
                              " --representatives 0.02 --threads 1";
  const pid_t pid = fork();
  if (pid == 0) {
    execl("/bin/sh", "sh", "-c", ("exec " + command + " >/dev/null 2>&1").c_str(), nullptr);
    _exit(127);
  }
  const fs::path checkpoint = root_ / "resumed.partial-fits.jsonl";
  for (int i = 0; i < 600; ++i) {
    std::ifstream in(checkpoint);
    const auto lines = std::count(std::istreambuf_iterator<char>(in), {}, '\n');
    if (lines >= 4) break;  // the header and three fits
    usleep(50000);
  }
  kill(pid, SIGINT);
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 130);
  EXPECT_FALSE(fs::exists(out / "material.json"));
  const auto resumed = RunSvbtdf("fit " + Processed() + " --out " + out.string() + " --representatives 0.02");
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_EQ(resumed.output.find(" 0 resumed"), std::string::npos) << resumed.output;
  EXPECT_FALSE(fs::exists(checkpoint));
  // Resumed or not, the material is the same.
  const auto direct = RunSvbtdf("fit " + Processed() + " --out " + (root_ / "direct").string() + " --representatives 0.02");
  ASSERT_EQ(direct.exit_code, 0) << direct.output;
  for (const char* map : {"alpha.exr", "k_s.exr", "shadowing_roughness.exr"}) {
    EXPECT_EQ(common::ReadFloatImage(out / map).pixels, common::ReadFloatImage(root_ / "direct" / map).pixels) << map;
  }
}

}  // namespace
}  // namespace svbtdf
