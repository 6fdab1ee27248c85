#pragma once
// Reading and writing the images svbtdf exchanges with users: camera-native frames as 16-bit
// PNG/TIFF (lossless, 1 or 3 channels) and linear maps as OpenEXR (half or float). Every failure
// throws svbtdf::Error naming the file; files are written atomically (temp, fsync, rename).

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace svbtdf::common {

// Camera-native values in [0, 2^bits_per_sample - 1], row-major, channels interleaved.
struct CameraImage {
  int width = 0, height = 0, channels = 1;
  int bits_per_sample = 16;
  std::vector<uint16_t> pixels;
  uint16_t at(int x, int y, int c = 0) const { return pixels[(static_cast<size_t>(y) * width + x) * channels + c]; }
};

// Linear floating-point values, row-major, channels interleaved.
struct FloatImage {
  int width = 0, height = 0, channels = 1;
  std::vector<float> pixels;
  FloatImage() = default;
  FloatImage(int w, int h, int c, float value = 0.0f)
      : width(w), height(h), channels(c), pixels(static_cast<size_t>(w) * h * c, value) {}
  float& at(int x, int y, int c = 0) { return pixels[(static_cast<size_t>(y) * width + x) * channels + c]; }
  float at(int x, int y, int c = 0) const { return pixels[(static_cast<size_t>(y) * width + x) * channels + c]; }
};

// Reads an 8- or 16-bit integer image (PNG, TIFF, ...) without rescaling its values; 8-bit files
// report bits_per_sample = 8. Throws for missing, unreadable or truncated files, float files and
// channel counts other than 1 or 3 (an alpha channel is dropped).
CameraImage ReadCameraImage(const std::filesystem::path& path);

// Writes a 16-bit PNG (or TIFF when the extension says so). With overwrite == false an existing
// file is an error and is left untouched.
void WriteCameraImage(const std::filesystem::path& path, const CameraImage& image, bool overwrite = false);

// Writes an 8-bit RGB PNG (pictures for people: report figures and plots, not data); `pixels` are
// row-major, width * height * 3 bytes. With overwrite == false an existing file is an error.
void WriteRgb8Png(const std::filesystem::path& path, const std::vector<uint8_t>& pixels, int width, int height,
                  bool overwrite = false);

// Reads any image OpenImageIO can decode as float (EXR, but also PNG/TIFF scaled to [0, 1]).
FloatImage ReadFloatImage(const std::filesystem::path& path);

// Writes an OpenEXR file (half precision by default: maps whose values need more than 11 bits
// of mantissa ask for full float). Channel names: Y; R,G,B; or A0..An for other counts.
void WriteFloatImage(const std::filesystem::path& path, const FloatImage& image, bool half_precision = true,
                     bool overwrite = true);

// Throws svbtdf::Error(kFormat) naming `source` and the first offending pixel when the image
// holds NaN or infinite values.
void RequireFinite(const FloatImage& image, const std::string& source);

}  // namespace svbtdf::common
