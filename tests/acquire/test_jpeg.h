#pragma once
// Encodes small test images as JPEG with libjpeg, for the MJPEG and DSLR decode paths.
#include <jpeglib.h>

#include <cstdint>
#include <cstdlib>
#include <vector>

namespace svbtdf::acquire::testing {

// A width x height RGB image whose red channel ramps with x and green with y; quality 100.
inline std::vector<uint8_t> EncodeTestJpeg(int width, int height) {
  jpeg_compress_struct info{};
  jpeg_error_mgr errors{};
  info.err = jpeg_std_error(&errors);
  jpeg_create_compress(&info);
  unsigned char* buffer = nullptr;
  unsigned long size = 0;
  jpeg_mem_dest(&info, &buffer, &size);
  info.image_width = width;
  info.image_height = height;
  info.input_components = 3;
  info.in_color_space = JCS_RGB;
  jpeg_set_defaults(&info);
  jpeg_set_quality(&info, 100, TRUE);
  jpeg_start_compress(&info, TRUE);
  std::vector<uint8_t> row(3 * width);
  while (info.next_scanline < info.image_height) {
    for (int x = 0; x < width; ++x) {
      row[3 * x] = static_cast<uint8_t>(255 * x / (width - 1));
      row[3 * x + 1] = static_cast<uint8_t>(255 * info.next_scanline / (height - 1));
      row[3 * x + 2] = 64;
    }
    JSAMPROW rows[1] = {row.data()};
    jpeg_write_scanlines(&info, rows, 1);
  }
  jpeg_finish_compress(&info);
  jpeg_destroy_compress(&info);
  std::vector<uint8_t> jpeg(buffer, buffer + size);
  std::free(buffer);
  return jpeg;
}

}  // namespace svbtdf::acquire::testing
