#pragma once
// Comparing a rendering with a reference (docs/validation.md, "Novel views"), and showing one.

#include <cstdint>
#include <vector>

#include "svbtdf/common/image_io.h"

namespace svbtdf::render {

// sqrt(sum (a - b)^2 / sum b^2) over every pixel and channel. Throws svbtdf::Error(kInvalidInput)
// when the images differ in size or channels, or the reference is all zero.
double RelativeRmse(const common::FloatImage& image, const common::FloatImage& reference);

// The structural similarity (Wang, Bovik, Sheikh, Simoncelli 2004) of what people see: the
// luminance of both images tone-mapped by ToSrgb8's curve (clamped to [0, 1]), an 11 x 11
// Gaussian window of sigma 1.5, K1 = 0.01, K2 = 0.03, dynamic range 1; the mean over the
// windows that fit inside the image. 1 for identical images.
double Ssim(const common::FloatImage& image, const common::FloatImage& reference);

// The sRGB encoding of linear values times `exposure`, clamped to [0, 1], as 8-bit RGB (a 1-channel
// image is shown grey): the PNG people look at.
std::vector<uint8_t> ToSrgb8(const common::FloatImage& image, double exposure = 1.0);

}  // namespace svbtdf::render
