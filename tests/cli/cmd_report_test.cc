// `svbtdf report MATERIAL --out DIR`: the pictures and the page, and the folder rules.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "run_command.h"
#include "small_material.h"
#include "svbtdf/common/image_io.h"

namespace svbtdf {
namespace {
namespace fs = std::filesystem;
using testing::RunSvbtdf;

fs::path Scratch() {
  const fs::path dir = fs::temp_directory_path() / ("svbtdf_report_test_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

TEST(ReportCommand, WritesMapsAndNdfPicturesAndAPage) {
  const fs::path dir = Scratch();
  fit::WriteMaterial(dir / "material", SmallMaterial());
  const auto result = RunSvbtdf("report " + (dir / "material").string() + " --out " + (dir / "report").string());
  ASSERT_EQ(result.exit_code, 0) << result.output;
  for (const char* file : {"index.html", "alpha.png", "k_s.png", "rho_d.png", "shadowing.png", "residual.png", "ndf_0.png"}) {
    EXPECT_TRUE(fs::exists(dir / "report" / file)) << file;
  }
  // Small maps are enlarged to at least 256 pixels by replication (3x2 -> 255x170 at scale 85).
  const common::CameraImage alpha = common::ReadCameraImage(dir / "report" / "alpha.png");
  EXPECT_EQ(alpha.width, 3 * 85);
  EXPECT_EQ(alpha.height, 2 * 85);
  // A constant alpha map is one colour.
  for (size_t k = 3; k < alpha.pixels.size(); ++k) EXPECT_EQ(alpha.pixels[k], alpha.pixels[k % 3]);
  std::stringstream html;
  html << std::ifstream(dir / "report" / "index.html").rdbuf();
  EXPECT_NE(html.str().find("ndf_0.png"), std::string::npos);
  // The report never writes into a folder that holds something.
  const auto again = RunSvbtdf("report " + (dir / "material").string() + " --out " + (dir / "report").string());
  EXPECT_EQ(again.exit_code, 2) << again.output;
  EXPECT_NE(again.output.find("is not empty"), std::string::npos) << again.output;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace svbtdf
