#include "svbtdf/acquire/pattern_raster.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "svbtdf/common/error.h"

namespace svbtdf::acquire {
namespace {

constexpr int kSupersampling = 16;
constexpr double kHalfDiagonal = 0.70710678118654752;

void CheckDot(double x, double y, double radius) {
  if (!std::isfinite(x) || !std::isfinite(y)) common::ThrowInvalidInput("pattern", "dot position is not finite");
  if (!(radius > 0.0) || !std::isfinite(radius)) common::ThrowInvalidInput("pattern", "dot radius must be positive");
}

// Adds the disk's coverage to `coverage` (saturating at 1: dots of a grid do not overlap).
void AddDisk(double cx, double cy, double radius, int width, int height,
             std::vector<float>* coverage) {
  const int x0 = std::max(0, static_cast<int>(std::floor(cx - radius - 1.0)));
  const int x1 = std::min(width - 1, static_cast<int>(std::ceil(cx + radius + 1.0)));
  const int y0 = std::max(0, static_cast<int>(std::floor(cy - radius - 1.0)));
  const int y1 = std::min(height - 1, static_cast<int>(std::ceil(cy + radius + 1.0)));
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      float& cell = (*coverage)[static_cast<size_t>(y) * width + x];
      cell = std::min(1.0f, cell + static_cast<float>(DiskCoverage(x, y, cx, cy, radius)));
    }
  }
}

struct BoardGeometry {
  double x0, y0, square;  // top-left corner of the board (pixel boundary) and square size
  int cols, rows;         // squares
};

BoardGeometry Board(const Pattern& pattern, int width, int height) {
  if (pattern.board_cols < 1 || pattern.board_rows < 1 || !(pattern.board_square_px >= 2.0)) {
    common::ThrowInvalidInput("pattern", "chessboard needs at least 1x1 inner corners and squares >= 2 px");
  }
  BoardGeometry board;
  board.square = pattern.board_square_px;
  board.cols = pattern.board_cols + 1;
  board.rows = pattern.board_rows + 1;
  const double board_w = board.cols * board.square, board_h = board.rows * board.square;
  if (board_w + 2 * board.square > width || board_h + 2 * board.square > height) {
    common::ThrowInvalidInput("pattern", "chessboard of " + std::to_string(board.cols) + "x" +
                                     std::to_string(board.rows) + " squares of " +
                                     std::to_string(board.square) + " px with its margin does not fit " +
                                     std::to_string(width) + "x" + std::to_string(height),
                      "use smaller squares or fewer corners");
  }
  // Pixel i spans [i - 0.5, i + 0.5]: start on a pixel boundary.
  board.x0 = std::round((width - board_w) / 2.0) - 0.5;
  board.y0 = std::round((height - board_h) / 2.0) - 0.5;
  return board;
}

}  // namespace

uint8_t EncodeIntensity(double linear, double gamma) {
  const double clamped = std::clamp(linear, 0.0, 1.0);
  return static_cast<uint8_t>(std::lround(255.0 * std::pow(clamped, 1.0 / gamma)));
}

double DiskCoverage(double px, double py, double cx, double cy, double radius) {
  const double distance = std::hypot(px - cx, py - cy);
  if (distance <= radius - kHalfDiagonal) return 1.0;
  if (distance >= radius + kHalfDiagonal) return 0.0;
  int inside = 0;
  const double r2 = radius * radius;
  for (int sy = 0; sy < kSupersampling; ++sy) {
    const double dy = py - 0.5 + (sy + 0.5) / kSupersampling - cy;
    for (int sx = 0; sx < kSupersampling; ++sx) {
      const double dx = px - 0.5 + (sx + 0.5) / kSupersampling - cx;
      inside += dx * dx + dy * dy <= r2;
    }
  }
  return static_cast<double>(inside) / (kSupersampling * kSupersampling);
}

std::pair<double, double> ChessboardCornerPx(const Pattern& pattern, int width, int height,
                                             int col, int row) {
  const BoardGeometry board = Board(pattern, width, height);
  return {board.x0 + (col + 1) * board.square, board.y0 + (row + 1) * board.square};
}

std::vector<uint8_t> RasterizePattern(const Pattern& pattern, int width, int height, double gamma) {
  if (width <= 0 || height <= 0) common::ThrowInvalidInput("display", "has no pixels");
  if (!(gamma > 0.0) || !std::isfinite(gamma)) common::ThrowInvalidInput("display", "gamma must be positive");
  if (!(pattern.intensity >= 0.0 && pattern.intensity <= 1.0)) {
    common::ThrowInvalidInput("pattern", "intensity must lie in [0, 1] (linear emitted intensity)");
  }
  const size_t count = static_cast<size_t>(width) * height;
  const uint8_t white = EncodeIntensity(pattern.intensity, gamma);
  switch (pattern.kind) {
    case Pattern::Kind::kBlack:
      return std::vector<uint8_t>(count, 0);
    case Pattern::Kind::kFlatWhite:
      return std::vector<uint8_t>(count, white);
    case Pattern::Kind::kDot:
    case Pattern::Kind::kAllDots: {
      std::vector<float> coverage(count, 0.0f);
      if (pattern.kind == Pattern::Kind::kDot) {
        CheckDot(pattern.x_px, pattern.y_px, pattern.dot_radius_px);
        AddDisk(pattern.x_px, pattern.y_px, pattern.dot_radius_px, width, height, &coverage);
      } else {
        for (const auto& [x, y] : pattern.all_dots_px) {
          CheckDot(x, y, pattern.dot_radius_px);
          AddDisk(x, y, pattern.dot_radius_px, width, height, &coverage);
        }
      }
      std::vector<uint8_t> codes(count, 0);
      for (size_t i = 0; i < count; ++i) {
        if (coverage[i] > 0.0f) codes[i] = EncodeIntensity(coverage[i] * pattern.intensity, gamma);
      }
      return codes;
    }
    case Pattern::Kind::kChessboard: {
      const BoardGeometry board = Board(pattern, width, height);
      std::vector<uint8_t> codes(count, 0);
      for (int y = 0; y < height; ++y) {
        const int square_y = static_cast<int>(std::floor((y - board.y0) / board.square));
        if (square_y < -1 || square_y > board.rows) continue;
        for (int x = 0; x < width; ++x) {
          const int square_x = static_cast<int>(std::floor((x - board.x0) / board.square));
          if (square_x < -1 || square_x > board.cols) continue;
          const bool margin = square_x < 0 || square_y < 0 || square_x >= board.cols || square_y >= board.rows;
          const bool white_square = (square_x + square_y) % 2 == 1;
          codes[static_cast<size_t>(y) * width + x] = (margin || white_square) ? white : 0;
        }
      }
      return codes;
    }
  }
  return std::vector<uint8_t>(count, 0);
}

}  // namespace svbtdf::acquire
