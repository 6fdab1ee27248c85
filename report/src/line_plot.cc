#include "svbtdf/report/line_plot.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdint>

#include "svbtdf/common/image_io.h"

namespace svbtdf::report {
namespace {

constexpr int kMarginLeft = 64;
constexpr int kMarginRight = 16;
constexpr int kMarginTop = 16;
constexpr int kMarginBottom = 36;
constexpr int kGlyphScale = 2;  // 5x7 glyphs drawn at 10x14 pixels

// 5x7 bitmaps, one 5-bit row per entry, most significant bit on the left.
struct Glyph {
  char c;
  std::array<uint8_t, 7> rows;
};
constexpr Glyph kGlyphs[] = {
    {'0', {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E}}, {'1', {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'2', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F}}, {'3', {0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E}},
    {'4', {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02}}, {'5', {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E}},
    {'6', {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E}}, {'7', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}},
    {'8', {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E}}, {'9', {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C}},
    {'.', {0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C}}, {'-', {0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00}},
};

class Canvas {
 public:
  Canvas(int width, int height) : width_(width), height_(height), pixels_(width * height * 3, 255) {}

  // Blends `color` into pixel (x, y) with coverage in [0, 1].
  void Blend(int x, int y, const Rgb8& color, double coverage) {
    if (x < 0 || y < 0 || x >= width_ || y >= height_ || coverage <= 0) return;
    coverage = std::min(1.0, coverage);
    unsigned char* p = &pixels_[(static_cast<size_t>(y) * width_ + x) * 3];
    for (int k = 0; k < 3; ++k) p[k] = static_cast<unsigned char>(std::lround(p[k] + coverage * (color[k] - p[k])));
  }

  // Anti-aliased segment of the given width: coverage falls off over one pixel at the edge.
  void Line(double x0, double y0, double x1, double y1, double width, const Rgb8& color) {
    const double half = 0.5 * width;
    const int left = static_cast<int>(std::floor(std::min(x0, x1) - half - 1));
    const int right = static_cast<int>(std::ceil(std::max(x0, x1) + half + 1));
    const int top = static_cast<int>(std::floor(std::min(y0, y1) - half - 1));
    const int bottom = static_cast<int>(std::ceil(std::max(y0, y1) + half + 1));
    const double dx = x1 - x0, dy = y1 - y0;
    const double length2 = dx * dx + dy * dy;
    for (int y = std::max(0, top); y <= std::min(height_ - 1, bottom); ++y) {
      for (int x = std::max(0, left); x <= std::min(width_ - 1, right); ++x) {
        const double px = x + 0.5 - x0, py = y + 0.5 - y0;
        const double t = length2 > 0 ? std::clamp((px * dx + py * dy) / length2, 0.0, 1.0) : 0.0;
        const double distance = std::hypot(px - t * dx, py - t * dy);
        Blend(x, y, color, half + 0.5 - distance);
      }
    }
  }

  void Text(int x, int y, const std::string& text, const Rgb8& color) {
    for (char c : text) {
      for (const Glyph& glyph : kGlyphs) {
        if (glyph.c != c) continue;
        for (int row = 0; row < 7; ++row) {
          for (int column = 0; column < 5; ++column) {
            if (!(glyph.rows[row] & (0x10 >> column))) continue;
            for (int sy = 0; sy < kGlyphScale; ++sy) {
              for (int sx = 0; sx < kGlyphScale; ++sx) {
                Blend(x + column * kGlyphScale + sx, y + row * kGlyphScale + sy, color, 1.0);
              }
            }
          }
        }
      }
      x += 6 * kGlyphScale;
    }
  }

  static int TextWidth(const std::string& text) { return static_cast<int>(text.size()) * 6 * kGlyphScale; }

  std::vector<unsigned char> Take() { return std::move(pixels_); }

 private:
  int width_, height_;
  std::vector<unsigned char> pixels_;
};

// A "nice" tick spacing (1, 2 or 5 times a power of ten) giving about `target` ticks over span.
double TickStep(double span, int target) {
  const double raw = span / target;
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  for (double factor : {1.0, 2.0, 5.0}) {
    if (factor * power >= raw) return factor * power;
  }
  return 10.0 * power;
}

std::string FormatTick(double value, double step) {
  const int decimals = std::max(0, static_cast<int>(-std::floor(std::log10(step) + 1e-9)));
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.*f", decimals, std::abs(value) < 1e-12 * step ? 0.0 : value);
  return buffer;
}

}  // namespace

void LinePlot::FitYRangeFromZero() {
  double top = 0.0;
  for (const PlotSeries& s : series) {
    for (size_t k = 0; k < s.y.size(); ++k) {
      top = std::max(top, s.y[k] + (s.error.empty() ? 0.0 : s.error[k]));
    }
  }
  y_min = 0.0;
  y_max = top > 0 ? 1.05 * top : 1.0;
}

std::vector<unsigned char> LinePlot::Render() const {
  Canvas canvas(width, height);
  const int plot_w = width - kMarginLeft - kMarginRight;
  const int plot_h = height - kMarginTop - kMarginBottom;
  const auto to_x = [&](double x) { return kMarginLeft + (x - x_min) / (x_max - x_min) * plot_w; };
  const auto to_y = [&](double y) { return kMarginTop + (1.0 - (y - y_min) / (y_max - y_min)) * plot_h; };
  const Rgb8 grid = {225, 225, 225};
  const Rgb8 ink = {40, 40, 40};

  const double x_step = TickStep(x_max - x_min, 8);
  for (double x = std::ceil(x_min / x_step) * x_step; x <= x_max + 1e-9 * x_step; x += x_step) {
    canvas.Line(to_x(x), kMarginTop, to_x(x), kMarginTop + plot_h, 1.0, grid);
    const std::string label = FormatTick(x, x_step);
    canvas.Text(static_cast<int>(to_x(x)) - Canvas::TextWidth(label) / 2, kMarginTop + plot_h + 8, label, ink);
  }
  const double y_step = TickStep(y_max - y_min, 6);
  for (double y = std::ceil(y_min / y_step) * y_step; y <= y_max + 1e-9 * y_step; y += y_step) {
    canvas.Line(kMarginLeft, to_y(y), kMarginLeft + plot_w, to_y(y), 1.0, grid);
    const std::string label = FormatTick(y, y_step);
    canvas.Text(kMarginLeft - 6 - Canvas::TextWidth(label), static_cast<int>(to_y(y)) - 7, label, ink);
  }
  canvas.Line(kMarginLeft, kMarginTop + plot_h, kMarginLeft + plot_w, kMarginTop + plot_h, 1.5, ink);
  canvas.Line(kMarginLeft, kMarginTop, kMarginLeft, kMarginTop + plot_h, 1.5, ink);

  for (const PlotSeries& s : series) {
    for (size_t k = 0; k + 1 < s.x.size() && s.line_width > 0; ++k) {
      canvas.Line(to_x(s.x[k]), to_y(s.y[k]), to_x(s.x[k + 1]), to_y(s.y[k + 1]), s.line_width, s.color);
    }
    if (s.error.empty()) continue;
    for (size_t k = 0; k < s.x.size(); ++k) {
      const double x = to_x(s.x[k]);
      canvas.Line(x, to_y(s.y[k] - s.error[k]), x, to_y(s.y[k] + s.error[k]), 1.5, s.color);
      canvas.Line(x - 2.5, to_y(s.y[k]), x + 2.5, to_y(s.y[k]), 5.0, s.color);
    }
  }
  return canvas.Take();
}

void LinePlot::WritePng(const std::filesystem::path& path) const { common::WriteRgb8Png(path, Render(), width, height); }

std::string HexColor(const Rgb8& color) {
  char buffer[8];
  std::snprintf(buffer, sizeof buffer, "#%02x%02x%02x", color[0], color[1], color[2]);
  return buffer;
}

}  // namespace svbtdf::report
