// The report page in a real browser (docs/report.md, "Checked in a browser"): the `tiny` preset
// simulated, fitted, rendered at one view and exported, its report opened from file:// in
// Debian's headless chromium by tools/report/browser_check.js (puppeteer-core, WebGL through
// SwiftShader). Label `browser`; part of the default run (about a minute).

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>

#include "../cli/run_command.h"
#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/json.h"
#include "temp_folder.h"

namespace svbtdf {
namespace {
namespace fs = std::filesystem;

const fs::path kTools = fs::path(SVBTDF_SOURCE_DIR) / "tools" / "report";

void RunOk(const std::string& arguments) {
  const testing::CommandResult result = testing::RunSvbtdf(arguments);
  ASSERT_EQ(result.exit_code, 0) << "svbtdf " << arguments << "\n" << result.output;
}

TEST(ReportInBrowser, LoadsDrawsTheSampleAndInspectsAClickedTexel) {
  ASSERT_TRUE(fs::is_directory(kTools / "node_modules" / "puppeteer-core")) << "run scripts/install-deps.sh (npm ci in tools/report)";
  ASSERT_TRUE(fs::is_regular_file("/usr/bin/chromium")) << "run scripts/install-deps.sh (it installs chromium)";
  const testing::TempFolder folder;
  const std::string dir = folder.path().string();
  ASSERT_NO_FATAL_FAILURE(RunOk("simulate --preset tiny --out " + dir + "/sim"));
  ASSERT_NO_FATAL_FAILURE(RunOk("run " + dir + "/sim/session --out " + dir + "/material --holdout 0.1"));
  ASSERT_NO_FATAL_FAILURE(RunOk("compare " + dir + "/material " + dir + "/sim/truth --json " + dir + "/compare.json"));
  fs::create_directories(folder / "render");
  const std::string view = " --view-deg 0 0 --resolution 64 64 --distance 0.3 --fov-deg 20 --background-distance 0.03 --checker-size 0.005";
  ASSERT_NO_FATAL_FAILURE(RunOk("render " + dir + "/sim/truth" + view + " --spp 16 --out " + dir + "/render/truth.exr --png " + dir +
                              "/render/truth.png --json " + dir + "/render/truth.json"));
  ASSERT_NO_FATAL_FAILURE(RunOk("render " + dir + "/material" + view + " --spp 16 --out " + dir + "/render/material.exr --png " + dir +
                              "/render/material.png --compare-to " + dir + "/render/truth.exr --json " + dir + "/render/material.json"));
  ASSERT_NO_FATAL_FAILURE(RunOk("export " + dir + "/material --gltf " + dir + "/gltf --threads 2"));
  ASSERT_NO_FATAL_FAILURE(RunOk("report " + dir + "/material --out " + dir + "/report --truth " + dir + "/sim/truth --compare " + dir +
                              "/compare.json --renders " + dir + "/render --gltf " + dir + "/gltf/material.gltf"));

  // Every file the page names exists (images, scripts, the stylesheet).
  const std::string html = common::ReadTextFile(folder / "report" / "index.html");
  const std::regex reference("(?:src|href)=\"([^\"#:]+)\"");
  int references = 0;
  for (auto it = std::sregex_iterator(html.begin(), html.end(), reference); it != std::sregex_iterator(); ++it, ++references) {
    EXPECT_TRUE(fs::is_regular_file(folder / "report" / (*it)[1].str())) << (*it)[1];
  }
  EXPECT_GT(references, 20);

  const fs::path json = folder / "browser.json";
  const std::string command = "node " + (kTools / "browser_check.js").string() + " " + (folder / "report" / "index.html").string() +
                              " --json " + json.string() + " > " + dir + "/browser.log 2>&1";
  const int status = std::system(command.c_str());
  ASSERT_EQ(status, 0) << common::ReadTextFile(folder / "browser.log");
  const nlohmann::json r = common::ReadJsonFile(json);
  EXPECT_TRUE(r["console_errors"].empty()) << r["console_errors"].dump(2);
  EXPECT_TRUE(r["page_errors"].empty()) << r["page_errors"].dump(2);
  EXPECT_TRUE(r["page_state_errors"].empty()) << r["page_state_errors"].dump(2);
  EXPECT_TRUE(r["failed_requests"].empty()) << r["failed_requests"].dump(2);
  for (const auto& image : r["images"]) EXPECT_TRUE(image["loaded"].get<bool>()) << image.dump();
  EXPECT_EQ(r["sections"], nlohmann::json({"live", "inspect", "maps", "numbers", "calibration", "validation"}));
  // The WebGL canvas shows the sample in both modes: many colours, most pixels unlike the corner.
  for (const char* mode : {"gltf", "sg"}) {
    ASSERT_TRUE(r["live"].contains(mode)) << mode;
    EXPECT_GT(r["live"][mode]["distinct_colours"].get<int>(), 50) << mode;
    EXPECT_GT(r["live"][mode]["differing_fraction"].get<double>(), 0.2) << mode;
  }
  // The clicked texel (20% across, 30% down the 32x32 map) is the one inspected, and its slices are drawn.
  ASSERT_TRUE(r["inspected"].is_object());
  EXPECT_NEAR(r["inspected"]["x"].get<int>(), 6, 1);
  EXPECT_NEAR(r["inspected"]["y"].get<int>(), 9, 1);
  EXPECT_NE(r["inspected"], r["inspected_before"]);
  EXPECT_GT(r["slice_measured"]["distinct_colours"].get<int>(), 10);
  EXPECT_GT(r["slice_fitted"]["distinct_colours"].get<int>(), 10);
  EXPECT_GT(r["ndf_fitted"]["distinct_colours"].get<int>(), 10);
  // The live spherical-Gaussian view was compared with svbtdf render of the fitted material.
  ASSERT_TRUE(r["sg_difference"].is_object());
  EXPECT_GT(r["sg_difference"]["pixels"].get<int>(), 100);
  EXPECT_LT(r["sg_difference"]["relative_rmse"].get<double>(), 0.5);
  std::printf("browser: load %.2f s, SG live view vs svbtdf render %.1f%% (%d pixels), whole check %.1f s\n",
              r["load_seconds"].get<double>(), 100 * r["sg_difference"]["relative_rmse"].get<double>(),
              r["sg_difference"]["pixels"].get<int>(), r["total_seconds"].get<double>());
}

}  // namespace
}  // namespace svbtdf
