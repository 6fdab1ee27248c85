#pragma once
// Turns the byte buffers that cameras hand out (raw Bayer mosaics, packed MIPI raw, grey, RGB,
// YUYV, JPEG) into Frames. Shared by the V4L2, libcamera and libgphoto2 drivers so that every
// backend interprets a given pixel format the same way.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "svbtdf/acquire/camera.h"

namespace svbtdf::acquire {

enum class SampleLayout {
  kRaw8,          // one byte per sample (Bayer or grey)
  kRaw16,         // little-endian 16-bit containers holding `bits` significant bits
  kMipiPacked10,  // 4 samples in 5 bytes (MIPI CSI-2 RAW10: four MSB bytes, then the 2-bit LSBs)
  kMipiPacked12,  // 2 samples in 3 bytes (MIPI CSI-2 RAW12)
  kRgb24,         // R, G, B bytes
  kBgr24,         // B, G, R bytes
  kYuyv,          // 4:2:2 Y0 U Y1 V, BT.601 limited range; converted to RGB (not linear)
  kJpeg,          // a JPEG stream (MJPEG frame or a DSLR's JPEG file; not linear)
};

struct PixelLayout {
  SampleLayout layout = SampleLayout::kRaw8;
  int bits = 8;             // significant bits per sample for the raw layouts
  std::string bayer;        // "RGGB" etc. for mosaics, empty for grey / colour
  std::string name;         // e.g. "SRGGB10", for messages and CameraInfo
};

// Decodes one image of `width` x `height` whose rows are `stride` bytes apart (ignored for
// JPEG). Throws Error(kHardware) naming `subject` when the buffer is shorter than the format
// requires or the JPEG is corrupt: a truncated frame is a camera fault, not user input.
Frame DecodeImage(const PixelLayout& layout, const uint8_t* data, size_t bytes, int width,
                  int height, size_t stride, const std::string& subject);

// Decodes a JPEG stream into an 8-bit frame (1 or 3 channels, linear = false).
Frame DecodeJpeg(const uint8_t* data, size_t bytes, const std::string& subject);

// Minimum bytes per row for `width` samples in this layout (0 for JPEG).
size_t MinimumStride(const PixelLayout& layout, int width);

}  // namespace svbtdf::acquire
