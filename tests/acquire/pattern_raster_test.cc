// The pattern rasteriser (acquire/src/pattern_raster.cc): gamma encoding of flat fields, dots
// with sub-pixel flux and centroid, the all-dots grid and the chessboard's geometry.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

#include "svbtdf/acquire/pattern_raster.h"
#include "svbtdf/common/error.h"

namespace svbtdf::acquire {
namespace {

constexpr double kPi = std::numbers::pi;

TEST(PatternRasterTest, GammaEncodingOfFlatFields) {
  Pattern white;
  white.kind = Pattern::Kind::kFlatWhite;
  white.intensity = 0.5;
  const auto codes = RasterizePattern(white, 4, 3, 2.2);
  EXPECT_EQ(codes[0], std::lround(255 * std::pow(0.5, 1 / 2.2)));  // 186, not 128
  EXPECT_EQ(codes[11], codes[0]);
  EXPECT_EQ(RasterizePattern(Pattern{}, 4, 3, 2.2), std::vector<uint8_t>(12, 0));
  white.intensity = 1.5;
  EXPECT_THROW(RasterizePattern(white, 4, 3, 2.2), common::Error);
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
  EXPECT_THROW(RasterizePattern(board, w, h, 2.2), common::Error);
}

}  // namespace
}  // namespace svbtdf::acquire
