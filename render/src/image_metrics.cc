#include "svbtdf/render/image_metrics.h"

#include <algorithm>
#include <cmath>

#include "svbtdf/common/error.h"

namespace svbtdf::render {
namespace {

void RequireSameShape(const common::FloatImage& a, const common::FloatImage& b) {
  if (a.width != b.width || a.height != b.height || a.channels != b.channels) {
    common::ThrowInvalidInput("image comparison", "the images differ in size or channels (" + std::to_string(a.width) + "x" +
                                                      std::to_string(a.height) + "x" + std::to_string(a.channels) + " against " +
                                                      std::to_string(b.width) + "x" + std::to_string(b.height) + "x" +
                                                      std::to_string(b.channels) + ")");
  }
}

double EncodeSrgb(double linear) {
  const double v = std::clamp(linear, 0.0, 1.0);
  return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
}

// The tone-mapped luminance SSIM compares (Rec. 709 weights of the encoded channels).
std::vector<double> DisplayedLuminance(const common::FloatImage& image) {
  std::vector<double> y(static_cast<size_t>(image.width) * image.height);
  for (int row = 0; row < image.height; ++row) {
    for (int col = 0; col < image.width; ++col) {
      double value = 0;
      if (image.channels < 3) {
        value = EncodeSrgb(image.at(col, row, 0));
      } else {
        value = 0.2126 * EncodeSrgb(image.at(col, row, 0)) + 0.7152 * EncodeSrgb(image.at(col, row, 1)) +
                0.0722 * EncodeSrgb(image.at(col, row, 2));
      }
      y[static_cast<size_t>(row) * image.width + col] = value;
    }
  }
  return y;
}

}  // namespace

double RelativeRmse(const common::FloatImage& image, const common::FloatImage& reference) {
  RequireSameShape(image, reference);
  double error = 0, norm = 0;
  for (size_t k = 0; k < image.pixels.size(); ++k) {
    const double d = static_cast<double>(image.pixels[k]) - reference.pixels[k];
    error += d * d;
    norm += static_cast<double>(reference.pixels[k]) * reference.pixels[k];
  }
  if (!(norm > 0)) common::ThrowInvalidInput("image comparison", "the reference image is black");
  return std::sqrt(error / norm);
}

double Ssim(const common::FloatImage& image, const common::FloatImage& reference) {
  RequireSameShape(image, reference);
  constexpr int kRadius = 5;  // 11 x 11
  constexpr double kSigma = 1.5, kC1 = 0.01 * 0.01, kC2 = 0.03 * 0.03;
  const int w = image.width, h = image.height;
  if (w < 2 * kRadius + 1 || h < 2 * kRadius + 1) common::ThrowInvalidInput("image comparison", "SSIM needs at least 11 x 11 pixels");
  double kernel[2 * kRadius + 1][2 * kRadius + 1];
  double total = 0;
  for (int dy = -kRadius; dy <= kRadius; ++dy) {
    for (int dx = -kRadius; dx <= kRadius; ++dx) {
      total += kernel[dy + kRadius][dx + kRadius] = std::exp(-(dx * dx + dy * dy) / (2 * kSigma * kSigma));
    }
  }
  const std::vector<double> a = DisplayedLuminance(image), b = DisplayedLuminance(reference);
  double sum = 0;
  int64_t windows = 0;
  for (int cy = kRadius; cy < h - kRadius; ++cy) {
    for (int cx = kRadius; cx < w - kRadius; ++cx) {
      double ma = 0, mb = 0, aa = 0, bb = 0, ab = 0;
      for (int dy = -kRadius; dy <= kRadius; ++dy) {
        for (int dx = -kRadius; dx <= kRadius; ++dx) {
          const double k = kernel[dy + kRadius][dx + kRadius] / total;
          const size_t p = static_cast<size_t>(cy + dy) * w + (cx + dx);
          ma += k * a[p];
          mb += k * b[p];
          aa += k * a[p] * a[p];
          bb += k * b[p] * b[p];
          ab += k * a[p] * b[p];
        }
      }
      const double va = aa - ma * ma, vb = bb - mb * mb, cov = ab - ma * mb;
      sum += (2 * ma * mb + kC1) * (2 * cov + kC2) / ((ma * ma + mb * mb + kC1) * (va + vb + kC2));
      ++windows;
    }
  }
  return sum / windows;
}

std::vector<uint8_t> ToSrgb8(const common::FloatImage& image, double exposure) {
  std::vector<uint8_t> rgb(static_cast<size_t>(image.width) * image.height * 3);
  for (int row = 0; row < image.height; ++row) {
    for (int col = 0; col < image.width; ++col) {
      for (int c = 0; c < 3; ++c) {
        const double linear = image.at(col, row, image.channels < 3 ? 0 : c) * exposure;
        rgb[(static_cast<size_t>(row) * image.width + col) * 3 + c] =
            static_cast<uint8_t>(std::lround(255.0 * EncodeSrgb(linear)));
      }
    }
  }
  return rgb;
}

}  // namespace svbtdf::render
