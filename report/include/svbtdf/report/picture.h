#pragma once
// 8-bit RGB pictures of maps and NDFs for the HTML pages: a perceptual colour ramp, scalar and
// colour maps, an NDF seen from above, and enlargement by pixel replication. Written as PNG
// through svbtdf/common/image_io.h.

#include <array>
#include <filesystem>
#include <vector>

#include "svbtdf/common/image_io.h"
#include "svbtdf/model/ndf.h"

namespace svbtdf::report {

using Rgb8 = std::array<unsigned char, 3>;

// A perceptually ordered ramp (viridis, five stops) over t in [0, 1], clamped; white for NaN.
Rgb8 Ramp(double t);

// An 8-bit RGB picture being drawn, row-major, white until drawn on.
struct Picture {
  int width = 0, height = 0;
  std::vector<unsigned char> pixels;  // width * height * 3
  Picture(int w, int h) : width(w), height(h), pixels(static_cast<size_t>(w) * h * 3, 255) {}
  void Set(int x, int y, const Rgb8& c);
  // Small maps would be unreadable at one pixel per texel: replicates each pixel by the largest
  // integer factor that keeps the longer side at most `min_side` (at least 1).
  Picture Enlarged(int min_side) const;
  // Writes a PNG (through image_io); refuses to overwrite an existing file.
  void WritePng(const std::filesystem::path& path) const;
};

// One scalar channel of a map, scaled from [lo, hi] to the ramp.
Picture ScalarMap(const common::FloatImage& map, int channel, double lo, double hi);
// An RGB map scaled so that `white` maps to 255, gamma 2.2.
Picture ColourMap(const common::FloatImage& map, double white);
// The NDF seen from above (orthographic over the hemisphere of h), ln D over its top 8 units.
Picture NdfPicture(const model::Ndf& ndf, int side);

}  // namespace svbtdf::report
