// report::LinePlot and report::Picture write 8-bit RGB PNGs through image_io that read back.
#include "svbtdf/report/line_plot.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "svbtdf/common/error.h"
#include "svbtdf/common/image_io.h"
#include "svbtdf/report/picture.h"

namespace svbtdf::report {
namespace {
namespace fs = std::filesystem;

class PngFigures : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("svbtdf-line-plot-" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(PngFigures, ALinePlotReadsBackAtItsSizeWithItsColours) {
  LinePlot plot;
  plot.width = 320;
  plot.height = 200;
  PlotSeries line;
  line.color = {200, 0, 0};
  line.line_width = 4.0;
  line.x = {0.0, 1.0};
  line.y = {0.5, 0.5};
  plot.series.push_back(line);
  plot.FitYRangeFromZero();
  EXPECT_DOUBLE_EQ(plot.y_max, 1.05 * 0.5);
  plot.WritePng(dir_ / "plot.png");

  const common::CameraImage image = common::ReadCameraImage(dir_ / "plot.png");
  EXPECT_EQ(image.width, 320);
  EXPECT_EQ(image.height, 200);
  EXPECT_EQ(image.channels, 3);
  EXPECT_EQ(image.bits_per_sample, 8);
  // What was rendered is what was written.
  const std::vector<unsigned char> rendered = plot.Render();
  ASSERT_EQ(image.pixels.size(), rendered.size());
  for (size_t k = 0; k < rendered.size(); ++k) ASSERT_EQ(image.pixels[k], rendered[k]) << k;
  // The top-right corner is background; the middle of the line is the series' colour.
  EXPECT_EQ(image.at(319, 0, 0), 255);
  const int mid_x = 64 + (320 - 64 - 16) / 2, mid_y = static_cast<int>(16 + (1 - 0.5 / plot.y_max) * (200 - 16 - 36));
  EXPECT_EQ(image.at(mid_x, mid_y, 0), 200);
  EXPECT_EQ(image.at(mid_x, mid_y, 1), 0);
}

TEST_F(PngFigures, APngIsNeverOverwritten) {
  LinePlot plot;
  plot.WritePng(dir_ / "plot.png");
  EXPECT_THROW(plot.WritePng(dir_ / "plot.png"), common::Error);
}

TEST_F(PngFigures, AnEnlargedPictureReplicatesItsPixels) {
  Picture picture(2, 1);
  picture.Set(1, 0, Ramp(1.0));
  const Picture big = picture.Enlarged(256);
  EXPECT_EQ(big.width, 256);
  EXPECT_EQ(big.height, 128);
  big.WritePng(dir_ / "picture.png");
  const common::CameraImage image = common::ReadCameraImage(dir_ / "picture.png");
  EXPECT_EQ(image.width, 256);
  EXPECT_EQ(image.at(0, 127, 0), 255);  // white where nothing was drawn
  EXPECT_EQ(image.at(255, 0, 0), 253);  // the ramp's yellow end
  EXPECT_EQ(image.at(128, 64, 2), 37);
}

TEST(HexColor, FormatsTheLegendColour) { EXPECT_EQ(HexColor({31, 119, 180}), "#1f77b4"); }

}  // namespace
}  // namespace svbtdf::report
