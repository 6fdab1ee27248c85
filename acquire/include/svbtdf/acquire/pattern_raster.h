#pragma once
// Rasterises display patterns into 8-bit code values, the exact image the SDL display shows.
// Pixel (i, j) is centred on monitor coordinate (i, j) (the OpenCV convention), so a dot at
// (10, 20) lights the pixel in column 10, row 20 most. Anti-aliasing is gamma-aware: a pixel
// that a disk of linear intensity I covers by a fraction c emits c * I, encoded as
// 255 * (c * I)^(1 / gamma), so the emitted flux of a dot is independent of its sub-pixel
// position and equals I * pi * r^2 pixel areas.

#include <cstdint>
#include <vector>

#include "svbtdf/acquire/display.h"

namespace svbtdf::acquire {

// Linear intensity in [0, 1] -> display code value in [0, 255].
uint8_t EncodeIntensity(double linear, double gamma);

// Fraction of the unit pixel centred on (px, py) covered by the disk (cx, cy, radius),
// from 16 x 16 supersampling.
double DiskCoverage(double px, double py, double cx, double cy, double radius);

// Single-channel code values, row-major, width * height. Throws Error(kInvalidInput) for
// non-finite positions, a radius <= 0, an intensity outside [0, 1] or a chessboard that does not
// fit the screen. The chessboard has (board_cols + 1) x (board_rows + 1) squares, top-left
// square black, centred on the screen, with a white margin one square wide for the detector.
std::vector<uint8_t> RasterizePattern(const Pattern& pattern, int width, int height, double gamma);

}  // namespace svbtdf::acquire

namespace svbtdf::acquire {

// Monitor-pixel position of inner corner (col, row) of the chessboard RasterizePattern draws,
// col in [0, board_cols), row in [0, board_rows). Corners fall on pixel boundaries.
std::pair<double, double> ChessboardCornerPx(const Pattern& pattern, int width, int height,
                                             int col, int row);

}  // namespace svbtdf::acquire
