#include "svbtdf/report/picture.h"

#include <algorithm>
#include <cmath>

namespace svbtdf::report {

Rgb8 Ramp(double t) {
  static constexpr double kStops[5][3] = {
      {68, 1, 84}, {59, 82, 139}, {33, 145, 140}, {94, 201, 98}, {253, 231, 37}};
  if (!std::isfinite(t)) return {255, 255, 255};
  t = std::clamp(t, 0.0, 1.0) * 4.0;
  const int k = std::min(3, static_cast<int>(t));
  const double f = t - k;
  Rgb8 c;
  for (int i = 0; i < 3; ++i) c[i] = static_cast<unsigned char>(std::lround((1 - f) * kStops[k][i] + f * kStops[k + 1][i]));
  return c;
}

void Picture::Set(int x, int y, const Rgb8& c) {
  std::copy(c.begin(), c.end(), pixels.begin() + (static_cast<size_t>(y) * width + x) * 3);
}

Picture Picture::Enlarged(int min_side) const {
  const int scale = std::max(1, min_side / std::max(1, std::max(width, height)));
  Picture big(width * scale, height * scale);
  for (int y = 0; y < big.height; ++y) {
    for (int x = 0; x < big.width; ++x) {
      const size_t from = (static_cast<size_t>(y / scale) * width + x / scale) * 3;
      std::copy_n(pixels.begin() + from, 3, big.pixels.begin() + (static_cast<size_t>(y) * big.width + x) * 3);
    }
  }
  return big;
}

void Picture::WritePng(const std::filesystem::path& path) const { common::WriteRgb8Png(path, pixels, width, height); }

Picture ScalarMap(const common::FloatImage& map, int channel, double lo, double hi) {
  Picture p(map.width, map.height);
  for (int y = 0; y < map.height; ++y) {
    for (int x = 0; x < map.width; ++x) p.Set(x, y, Ramp((map.at(x, y, channel) - lo) / (hi - lo)));
  }
  return p;
}

Picture ColourMap(const common::FloatImage& map, double white) {
  Picture p(map.width, map.height);
  for (int y = 0; y < map.height; ++y) {
    for (int x = 0; x < map.width; ++x) {
      Rgb8 c;
      for (int k = 0; k < 3; ++k) {
        c[k] = static_cast<unsigned char>(std::lround(255 * std::pow(std::clamp(map.at(x, y, k) / white, 0.0, 1.0), 1 / 2.2)));
      }
      p.Set(x, y, c);
    }
  }
  return p;
}

Picture NdfPicture(const model::Ndf& ndf, int side) {
  Picture p(side, side);
  std::vector<double> ln_d(static_cast<size_t>(side) * side, std::nan(""));
  double peak = -1e300;
  for (int y = 0; y < side; ++y) {
    for (int x = 0; x < side; ++x) {
      const double u = (x + 0.5) / side * 2 - 1, v = 1 - (y + 0.5) / side * 2;
      if (u * u + v * v >= 1) continue;
      const double d = ndf.D(model::Vec3(u, v, std::sqrt(1 - u * u - v * v)));
      ln_d[static_cast<size_t>(y) * side + x] = std::log(std::max(d, 1e-30));
      peak = std::max(peak, ln_d[static_cast<size_t>(y) * side + x]);
    }
  }
  for (int y = 0; y < side; ++y) {
    for (int x = 0; x < side; ++x) p.Set(x, y, Ramp((ln_d[static_cast<size_t>(y) * side + x] - peak + 8) / 8));
  }
  return p;
}

}  // namespace svbtdf::report
