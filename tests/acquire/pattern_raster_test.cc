// Frame decoding shared by the drivers, the pattern rasteriser, and the SDL display under SDL's
// headless "dummy" video driver (rendered pixels read back where the renderer supports it).

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

#include "svbtdf/acquire/frame_decode.h"
#include "svbtdf/acquire/pattern_raster.h"
#include "svbtdf/acquire/sdl_display.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/interrupt.h"

namespace svbtdf::acquire {
namespace {

constexpr double kPi = 3.14159265358979323846;

TEST(FrameDecodeTest, UnpacksMipiRaw10And12) {
  // RAW10: samples 0x3FF, 0x000, 0x155, 0x2AA -> MSBs FF 00 55 AA, LSB byte 11 00 01 10 b.
  const uint8_t raw10[] = {0xFF, 0x00, 0x55, 0xAA, 0b10010011};
  const Frame ten = DecodeImage({SampleLayout::kMipiPacked10, 10, "RGGB", "p"}, raw10, 5, 4, 1, 5, "t");
  EXPECT_EQ(ten.pixels, (std::vector<uint16_t>{0x3FF, 0x000, 0x155, 0x2AA}));
  EXPECT_EQ(ten.bits_per_sample, 10);
  // RAW12: samples 0xABC, 0x123 -> AB 12 then LSB nibbles C (low) and 3 (high) = 0x3C.
  const uint8_t raw12[] = {0xAB, 0x12, 0x3C};
  const Frame twelve = DecodeImage({SampleLayout::kMipiPacked12, 12, "", "p"}, raw12, 3, 2, 1, 3, "t");
  EXPECT_EQ(twelve.pixels, (std::vector<uint16_t>{0xABC, 0x123}));
}

TEST(FrameDecodeTest, RespectsStrideAndMasksUnusedBits) {
  // Two rows of two 10-bit samples in 16-bit containers, rows padded to 6 bytes; the padding
  // and the top bits (set to garbage) must not leak into the samples.
  const uint8_t data[] = {0x01, 0xFC, 0x02, 0x00, 0xEE, 0xEE, 0xFF, 0x03, 0x04, 0x00, 0xEE, 0xEE};
  const Frame frame = DecodeImage({SampleLayout::kRaw16, 10, "BGGR", "SBGGR10"}, data, sizeof data, 2, 2, 6, "t");
  EXPECT_EQ(frame.pixels, (std::vector<uint16_t>{0x001, 0x002, 0x3FF, 0x004}));
  try {
    DecodeImage({SampleLayout::kRaw16, 10, "", ""}, data, 9, 2, 2, 6, "cam");
    FAIL() << "a short frame must be rejected";
  } catch (const Error& error) {
    EXPECT_EQ(error.kind(), ErrorKind::kHardware);
  }
}

TEST(FrameDecodeTest, YuyvLimitedRangeGreysAndBgrOrder) {
  const uint8_t yuyv[] = {16, 128, 235, 128};
  const Frame grey = DecodeImage({SampleLayout::kYuyv, 8, "", "YUYV"}, yuyv, 4, 2, 1, 4, "t");
  EXPECT_EQ(grey.pixels, (std::vector<uint16_t>{0, 0, 0, 255, 255, 255}));
  EXPECT_FALSE(grey.linear);
  const uint8_t bgr[] = {1, 2, 3};
  EXPECT_EQ(DecodeImage({SampleLayout::kBgr24, 8, "", "BGR3"}, bgr, 3, 1, 1, 3, "t").pixels,
            (std::vector<uint16_t>{3, 2, 1}));
}

TEST(PatternRasterTest, GammaEncodingOfFlatFields) {
  Pattern white;
  white.kind = Pattern::Kind::kFlatWhite;
  white.intensity = 0.5;
  const auto codes = RasterizePattern(white, 4, 3, 2.2);
  EXPECT_EQ(codes[0], std::lround(255 * std::pow(0.5, 1 / 2.2)));  // 186, not 128
  EXPECT_EQ(codes[11], codes[0]);
  EXPECT_EQ(RasterizePattern(Pattern{}, 4, 3, 2.2), std::vector<uint8_t>(12, 0));
  white.intensity = 1.5;
  EXPECT_THROW(RasterizePattern(white, 4, 3, 2.2), Error);
}

// Decodes code values back to linear intensity and returns flux and centroid.
void Moments(const std::vector<uint8_t>& codes, int width, double gamma, double* flux, double* cx, double* cy) {
  *flux = *cx = *cy = 0.0;
  for (size_t i = 0; i < codes.size(); ++i) {
    const double linear = std::pow(codes[i] / 255.0, gamma);
    *flux += linear;
    *cx += linear * static_cast<double>(i % width);
    *cy += linear * static_cast<double>(i / width);
  }
  *cx /= *flux;
  *cy /= *flux;
}

TEST(PatternRasterTest, DotFluxAndCentroidAreSubPixelAccurate) {
  // Emitted flux must equal I * pi r^2 and the centroid the requested centre wherever the dot
  // sits relative to the pixel grid (8-bit quantisation and 16x16 supersampling bound both).
  const double gamma = 2.2;
  for (double radius : {1.5, 3.0, 6.0}) {
    for (double offset : {0.0, 0.13, 0.5, 0.77}) {
      Pattern dot;
      dot.kind = Pattern::Kind::kDot;
      dot.x_px = 20.0 + offset;
      dot.y_px = 15.0 + 0.6 * offset;
      dot.dot_radius_px = radius;
      dot.intensity = 0.8;
      double flux, cx, cy;
      Moments(RasterizePattern(dot, 40, 30, gamma), 40, gamma, &flux, &cx, &cy);
      const double expected = 0.8 * kPi * radius * radius;
      EXPECT_NEAR(flux / expected, 1.0, 0.02) << "r " << radius << " offset " << offset;
      EXPECT_NEAR(cx, dot.x_px, 0.02) << "r " << radius;
      EXPECT_NEAR(cy, dot.y_px, 0.02) << "r " << radius;
    }
  }
}

TEST(PatternRasterTest, AllDotsAndChessboardGeometry) {
  Pattern grid;
  grid.kind = Pattern::Kind::kAllDots;
  grid.dot_radius_px = 2.0;
  grid.all_dots_px = {{10, 10}, {30, 10}, {10.5, 25.5}};
  const auto dots = RasterizePattern(grid, 40, 40, 2.2);
  EXPECT_EQ(dots[10 * 40 + 10], 255);
  EXPECT_EQ(dots[10 * 40 + 30], 255);
  EXPECT_EQ(dots[20 * 40 + 20], 0);
  double flux, cx, cy;
  Moments(dots, 40, 2.2, &flux, &cx, &cy);
  EXPECT_NEAR(flux / (3 * kPi * 4.0), 1.0, 0.03);

  Pattern board;
  board.kind = Pattern::Kind::kChessboard;
  board.board_cols = 4;
  board.board_rows = 3;
  board.board_square_px = 10;
  const int w = 80, h = 70;
  const auto codes = RasterizePattern(board, w, h, 2.2);
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 4; ++col) {
      const auto [x, y] = ChessboardCornerPx(board, w, h, col, row);
      EXPECT_DOUBLE_EQ(x - std::floor(x), 0.5) << "corners lie on pixel boundaries";
      // The four pixels around an inner corner alternate black / white.
      const auto at = [&](double px, double py) {
        return codes[static_cast<size_t>(py) * w + static_cast<size_t>(px)];
      };
      const int tl = at(x - 0.5, y - 0.5), tr = at(x + 0.5, y - 0.5);
      const int bl = at(x - 0.5, y + 0.5), br = at(x + 0.5, y + 0.5);
      EXPECT_EQ(tl, br);
      EXPECT_EQ(tr, bl);
      EXPECT_NE(tl, tr);
    }
  }
  const auto [x0, y0] = ChessboardCornerPx(board, w, h, 0, 0);
  EXPECT_EQ(codes[static_cast<size_t>(y0 - 5.5) * w + static_cast<size_t>(x0 - 5.5)], 0)
      << "top-left square is black";
  EXPECT_EQ(codes[static_cast<size_t>(y0 - 15.5) * w + static_cast<size_t>(x0 - 5.5)], 255)
      << "white margin around the board";
  board.board_square_px = 30;
  EXPECT_THROW(RasterizePattern(board, w, h, 2.2), Error);
}

class SdlDummyTest : public ::testing::Test {
 protected:
  void SetUp() override { setenv("SDL_VIDEODRIVER", "dummy", /*overwrite=*/0); }
};

TEST_F(SdlDummyTest, ListsTheDummyDisplay) {
  std::vector<DisplayInfo> displays;
  try {
    displays = ListSdlDisplays();
  } catch (const Error& error) {
    GTEST_SKIP() << "SDL video unavailable: " << error.what();
  }
  ASSERT_FALSE(displays.empty());
  EXPECT_EQ(displays[0].id, "sdl:0");
  EXPECT_GT(displays[0].width_px, 0);
}

TEST_F(SdlDummyTest, ShowsExactlyTheRasterisedPattern) {
  std::unique_ptr<SdlDisplay> display;
  try {
    display = std::make_unique<SdlDisplay>(0, SdlDisplayOptions{});
  } catch (const Error& error) {
    GTEST_SKIP() << "SDL display unavailable: " << error.what();
  }
  const DisplayInfo info = display->Info();
  Pattern dot;
  dot.kind = Pattern::Kind::kDot;
  dot.x_px = info.width_px / 2.0 + 0.3;
  dot.y_px = info.height_px / 3.0 + 0.7;
  dot.dot_radius_px = 4.0;
  dot.intensity = 0.6;
  Pattern board;
  board.kind = Pattern::Kind::kChessboard;
  board.board_square_px = 40;
  for (const Pattern& pattern : {dot, board}) {
    display->Show(pattern);
    std::vector<uint8_t> shown;
    if (!display->ReadBackLastFrame(&shown)) {
      GTEST_SKIP() << "renderer '" << display->RendererName() << "' cannot read pixels back";
    }
    EXPECT_EQ(shown, RasterizePattern(pattern, info.width_px, info.height_px, info.gamma))
        << "renderer " << display->RendererName();
  }
  EXPECT_THROW(display->Show([] { Pattern p; p.kind = Pattern::Kind::kDot; p.dot_radius_px = -1; return p; }()), Error);
}

TEST_F(SdlDummyTest, RejectsAMissingDisplayIndex) {
  try {
    SdlDisplay display(99, {});
    FAIL() << "display 99 should not exist";
  } catch (const Error& error) {
    if (error.kind() == ErrorKind::kHardware) GTEST_SKIP() << "SDL video unavailable: " << error.what();
    EXPECT_EQ(error.kind(), ErrorKind::kInvalidInput);
  }
}

}  // namespace
}  // namespace svbtdf::acquire
