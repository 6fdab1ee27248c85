#include "svbtdf/acquire/frame_decode.h"

#include <jpeglib.h>

#include <algorithm>
#include <csetjmp>
#include <cstdio>
#include <string>

#include "svbtdf/common/error.h"

namespace svbtdf::acquire {
namespace {

[[noreturn]] void ThrowCorrupt(const std::string& subject, const std::string& problem) {
  throw common::Error(common::ErrorKind::kHardware, subject, problem,
              "the camera delivered a damaged frame; check the cable and retry");
}

uint16_t Clamp8(double v) { return static_cast<uint16_t>(std::clamp(v + 0.5, 0.0, 255.0)); }

// BT.601 limited-range YCbCr to R'G'B' (the usual webcam encoding).
void YcbcrToRgb(int y, int cb, int cr, uint16_t* rgb) {
  const double yy = 1.164383 * (y - 16);
  const double u = cb - 128, v = cr - 128;
  rgb[0] = Clamp8(yy + 1.596027 * v);
  rgb[1] = Clamp8(yy - 0.391762 * u - 0.812968 * v);
  rgb[2] = Clamp8(yy + 2.017232 * u);
}

struct JpegErrorManager {
  jpeg_error_mgr base;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

void JpegErrorExit(j_common_ptr info) {
  auto* manager = reinterpret_cast<JpegErrorManager*>(info->err);
  (*info->err->format_message)(info, manager->message);
  std::longjmp(manager->jump, 1);
}

void JpegSilence(j_common_ptr, int) {}

}  // namespace

size_t MinimumStride(const PixelLayout& layout, int width) {
  const auto w = static_cast<size_t>(width);
  switch (layout.layout) {
    case SampleLayout::kRaw8: return w;
    case SampleLayout::kRaw16: return 2 * w;
    case SampleLayout::kMipiPacked10: return (w * 10 + 7) / 8;
    case SampleLayout::kMipiPacked12: return (w * 12 + 7) / 8;
    case SampleLayout::kRgb24:
    case SampleLayout::kBgr24: return 3 * w;
    case SampleLayout::kYuyv: return 2 * w;
    case SampleLayout::kJpeg: return 0;
  }
  return 0;
}

Frame DecodeImage(const PixelLayout& layout, const uint8_t* data, size_t bytes, int width,
                  int height, size_t stride, const std::string& subject) {
  if (layout.layout == SampleLayout::kJpeg) return DecodeJpeg(data, bytes, subject);
  if (width <= 0 || height <= 0) ThrowCorrupt(subject, "frame has no pixels");
  const size_t row_bytes = MinimumStride(layout, width);
  if (stride < row_bytes) stride = row_bytes;
  const size_t needed = stride * static_cast<size_t>(height - 1) + row_bytes;
  if (bytes < needed) {
    ThrowCorrupt(subject, "short frame: " + std::to_string(bytes) + " bytes, " + layout.name +
                              " " + std::to_string(width) + "x" + std::to_string(height) +
                              " needs " + std::to_string(needed));
  }
  Frame frame;
  frame.width = width;
  frame.height = height;
  frame.bayer_pattern = layout.bayer;
  const bool colour = layout.layout == SampleLayout::kRgb24 ||
                      layout.layout == SampleLayout::kBgr24 || layout.layout == SampleLayout::kYuyv;
  frame.channels = colour ? 3 : 1;
  frame.bits_per_sample = colour ? 8 : layout.bits;
  frame.linear = layout.layout != SampleLayout::kYuyv;
  frame.pixels.resize(static_cast<size_t>(width) * height * frame.channels);
  const uint16_t mask = static_cast<uint16_t>((1u << frame.bits_per_sample) - 1u);
  uint16_t* out = frame.pixels.data();
  for (int y = 0; y < height; ++y) {
    const uint8_t* row = data + stride * y;
    switch (layout.layout) {
      case SampleLayout::kRaw8:
        for (int x = 0; x < width; ++x) *out++ = row[x];
        break;
      case SampleLayout::kRaw16:
        for (int x = 0; x < width; ++x) {
          *out++ = static_cast<uint16_t>(row[2 * x] | (row[2 * x + 1] << 8)) & mask;
        }
        break;
      case SampleLayout::kMipiPacked10:
        for (int x = 0; x < width; ++x) {
          const uint8_t* group = row + (x / 4) * 5;
          const int lsb = (group[4] >> (2 * (x % 4))) & 0x3;
          *out++ = static_cast<uint16_t>((group[x % 4] << 2) | lsb);
        }
        break;
      case SampleLayout::kMipiPacked12:
        for (int x = 0; x < width; ++x) {
          const uint8_t* group = row + (x / 2) * 3;
          const int lsb = (group[2] >> (4 * (x % 2))) & 0xF;
          *out++ = static_cast<uint16_t>((group[x % 2] << 4) | lsb);
        }
        break;
      case SampleLayout::kRgb24:
        for (int i = 0; i < 3 * width; ++i) *out++ = row[i];
        break;
      case SampleLayout::kBgr24:
        for (int x = 0; x < width; ++x) {
          *out++ = row[3 * x + 2];
          *out++ = row[3 * x + 1];
          *out++ = row[3 * x];
        }
        break;
      case SampleLayout::kYuyv:
        for (int x = 0; x + 1 < width; x += 2) {
          const uint8_t* q = row + 2 * x;
          YcbcrToRgb(q[0], q[1], q[3], out);
          YcbcrToRgb(q[2], q[1], q[3], out + 3);
          out += 6;
        }
        if (width % 2 == 1) {  // odd width: the last luma sample shares the previous chroma pair
          const uint8_t* q = row + 2 * (width - 1);
          YcbcrToRgb(q[0], width > 1 ? q[-1] : 128, q[1], out);
          out += 3;
        }
        break;
      case SampleLayout::kJpeg:
        break;
    }
  }
  return frame;
}

Frame DecodeJpeg(const uint8_t* data, size_t bytes, const std::string& subject) {
  if (data == nullptr || bytes < 4) ThrowCorrupt(subject, "empty JPEG frame");
  jpeg_decompress_struct info{};
  JpegErrorManager errors{};
  info.err = jpeg_std_error(&errors.base);
  errors.base.error_exit = JpegErrorExit;
  errors.base.emit_message = JpegSilence;
  Frame frame;  // constructed before setjmp so that a longjmp skips no destructor
  std::vector<uint8_t> row;
  if (setjmp(errors.jump) != 0) {
    jpeg_destroy_decompress(&info);
    ThrowCorrupt(subject, std::string("cannot decode JPEG: ") + errors.message);
  }
  jpeg_create_decompress(&info);
  jpeg_mem_src(&info, data, static_cast<unsigned long>(bytes));
  jpeg_read_header(&info, TRUE);
  // libjpeg-turbo supplies the standard Huffman tables that MJPEG webcams omit.
  info.out_color_space = info.num_components == 1 ? JCS_GRAYSCALE : JCS_RGB;
  jpeg_start_decompress(&info);
  frame.width = static_cast<int>(info.output_width);
  frame.height = static_cast<int>(info.output_height);
  frame.channels = info.output_components;
  frame.bits_per_sample = 8;
  frame.linear = false;
  frame.pixels.resize(static_cast<size_t>(frame.width) * frame.height * frame.channels);
  row.resize(static_cast<size_t>(frame.width) * frame.channels);
  while (info.output_scanline < info.output_height) {
    JSAMPROW rows[1] = {row.data()};
    const size_t y = info.output_scanline;
    jpeg_read_scanlines(&info, rows, 1);
    std::copy(row.begin(), row.end(), frame.pixels.begin() + y * row.size());
  }
  jpeg_finish_decompress(&info);
  jpeg_destroy_decompress(&info);
  return frame;
}

}  // namespace svbtdf::acquire
