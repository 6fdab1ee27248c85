#pragma once
// A minimal line-plot renderer for the figures of the pages (the validation page's
// cross-sections): axes with numbered ticks, anti-aliased polylines, points with error bars, written
// as an 8-bit RGB PNG through image_io. Titles and legends belong in the HTML page that shows the images; the
// raster only carries digits, so no font files are needed.

#include <filesystem>
#include <string>
#include <vector>

#include "svbtdf/report/picture.h"

namespace svbtdf::report {

struct PlotSeries {
  std::string name;  // for the HTML legend
  Rgb8 color = {0, 0, 0};
  std::vector<double> x, y;
  std::vector<double> error;  // optional symmetric error bars (points are drawn when present)
  double line_width = 2.0;    // pixels; 0 draws points only
};

struct LinePlot {
  std::vector<PlotSeries> series;
  double x_min = 0.0, x_max = 1.0;
  double y_min = 0.0, y_max = 1.0;
  int width = 640, height = 400;

  // Sets the y range to [0, 1.05 max] of all series (with error bars).
  void FitYRangeFromZero();
  // Renders to RGB8 (row-major, width * height * 3 bytes).
  std::vector<unsigned char> Render() const;
  // Renders and writes a PNG atomically; refuses to overwrite an existing file.
  void WritePng(const std::filesystem::path& path) const;
};

std::string HexColor(const Rgb8& color);  // "#rrggbb", for the HTML legend

}  // namespace svbtdf::report
