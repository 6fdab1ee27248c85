#include "png_reader.h"

#include <png.h>

#include <algorithm>
#include <cerrno>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <memory>
#include <vector>

#include "svbtdf/common/error.h"

namespace svbtdf::common {
namespace {

// libpng reports errors by calling back and expects the callback not to return: we keep the
// message and jump back into ReadRows (C++ exceptions must not unwind through libpng's C frames).
struct PngErrorState {
  std::jmp_buf jump;
  char message[256] = {};
};

void OnPngError(png_structp png, png_const_charp message) {
  auto* state = static_cast<PngErrorState*>(png_get_error_ptr(png));
  std::snprintf(state->message, sizeof(state->message), "%s", message);
  std::longjmp(state->jump, 1);
}

// Warnings (an sRGB profile libpng dislikes, an unknown chunk) do not affect the pixels.
void OnPngWarning(png_structp, png_const_charp) {}

struct FileCloser {
  void operator()(std::FILE* file) const { std::fclose(file); }
};

struct PngHeader {
  png_uint_32 width = 0, height = 0;
  int bit_depth = 0, color_type = 0, channels = 0, significant_bits = 0;
};

// Sets libpng's transformations so that every PNG reads as 8- or 16-bit gray or RGB in host byte
// order, without alpha, and says what it will read. Must run inside the setjmp of ReadRows.
PngHeader PrepareTransforms(png_structp png, png_infop info) {
  png_read_info(png, info);
  PngHeader header;
  header.width = png_get_image_width(png, info);
  header.height = png_get_image_height(png, info);
  header.bit_depth = png_get_bit_depth(png, info);
  header.color_type = png_get_color_type(png, info);
  if (header.color_type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if (header.color_type == PNG_COLOR_TYPE_GRAY && header.bit_depth < 8) png_set_expand_gray_1_2_4_to_8(png);
  if (header.color_type & PNG_COLOR_MASK_ALPHA) png_set_strip_alpha(png);
  if (header.bit_depth == 16) png_set_swap(png);  // PNG is big-endian
  png_set_interlace_handling(png);
  // A camera's 12-bit frame in a 16-bit PNG says so in sBIT (WriteCameraImage writes it).
  // (Not for 1-, 2- and 4-bit gray, which the expansion scales to 8 bits.)
  png_color_8p significant = nullptr;
  if (header.bit_depth >= 8 && png_get_sBIT(png, info, &significant) && significant) {
    header.significant_bits = header.color_type & PNG_COLOR_MASK_COLOR ? significant->red : significant->gray;
  }
  png_read_update_info(png, info);
  header.channels = png_get_channels(png, info);
  header.bit_depth = png_get_bit_depth(png, info);
  return header;
}

// libpng's read state, destroyed on every way out.
class PngReadState {
 public:
  explicit PngReadState(PngErrorState* errors)
      : png_(png_create_read_struct(PNG_LIBPNG_VER_STRING, errors, OnPngError, OnPngWarning)),
        info_(png_ ? png_create_info_struct(png_) : nullptr) {}
  ~PngReadState() { png_destroy_read_struct(&png_, &info_, nullptr); }
  PngReadState(const PngReadState&) = delete;
  PngReadState& operator=(const PngReadState&) = delete;
  bool ok() const { return info_ != nullptr; }
  png_structp png() const { return png_; }
  png_infop info() const { return info_; }

 private:
  png_structp png_;
  png_infop info_;
};

// The two steps that call into libpng, each returning false (message in `errors`) where libpng
// failed. Nothing in them is constructed after setjmp: longjmp would skip its destructor.
bool ReadHeader(std::FILE* file, const PngReadState& state, PngErrorState* errors, PngHeader* header) {
  if (setjmp(errors->jump)) return false;
  png_init_io(state.png(), file);
  png_set_sig_bytes(state.png(), 8);
  *header = PrepareTransforms(state.png(), state.info());
  return true;
}

bool ReadPixels(const PngReadState& state, PngErrorState* errors, png_uint_32 height, size_t row_bytes,
                unsigned char* pixels) {
  std::vector<png_bytep> rows(height);
  for (png_uint_32 y = 0; y < height; ++y) rows[y] = pixels + y * row_bytes;
  if (setjmp(errors->jump)) return false;
  png_read_image(state.png(), rows.data());
  png_read_end(state.png(), nullptr);
  return true;
}

}  // namespace

void RequireExistingFile(const std::filesystem::path& path) {
  std::error_code error;
  const bool exists = std::filesystem::exists(path, error);
  if (error) ThrowIoError(path.string(), "cannot be read: " + error.message());
  if (!exists) ThrowIoError(path.string(), "does not exist");
}

void RequireSaneImageSize(const std::filesystem::path& path, int64_t width, int64_t height, int channels) {
  // A header is a claim, not a fact: a few damaged bytes can claim 60000 x 60000 pixels, which
  // would end in "out of memory" without naming the file.
  // Compared by division: an EXR data window can claim 2^32 x 2^32 pixels, whose product
  // overflows int64_t.
  constexpr int64_t kMaxSamples = int64_t{1} << 30;
  if (width <= 0 || height <= 0 || width > kMaxSamples / height / std::max(1, channels)) {
    ThrowFormatError(path.string(), "claims " + std::to_string(width) + " x " + std::to_string(height) + " x " +
                                        std::to_string(channels) + " samples, more than svbtdf reads (2^30)",
                     "the file is damaged or not an image of this rig");
  }
}

CameraImage ReadPngCameraImage(const std::filesystem::path& path) {
  RequireExistingFile(path);
  std::unique_ptr<std::FILE, FileCloser> file(std::fopen(path.c_str(), "rb"));
  if (!file) ThrowIoError(path.string(), std::string("cannot be opened: ") + std::strerror(errno));
  unsigned char signature[8] = {};
  if (std::fread(signature, 1, sizeof(signature), file.get()) != sizeof(signature) ||
      png_sig_cmp(signature, 0, sizeof(signature)) != 0) {
    ThrowFormatError(path.string(), "is not a PNG file (its first 8 bytes are not PNG's signature)",
                     "is the file complete?");
  }
  PngErrorState errors;
  const PngReadState state(&errors);
  if (!state.ok()) ThrowIoError(path.string(), "cannot be decoded: libpng could not allocate its state");
  PngHeader header;
  if (!ReadHeader(file.get(), state, &errors, &header)) {
    ThrowFormatError(path.string(), std::string("is not a readable PNG: ") + errors.message);
  }
  RequireSaneImageSize(path, header.width, header.height, header.channels);  // before allocating
  const size_t row_bytes = png_get_rowbytes(state.png(), state.info());
  std::vector<unsigned char> bytes(row_bytes * header.height);
  if (!ReadPixels(state, &errors, header.height, row_bytes, bytes.data())) {
    ThrowFormatError(path.string(), std::string("is truncated or corrupt: ") + errors.message);
  }
  if (header.channels != 1 && header.channels != 3) {
    ThrowFormatError(path.string(), "has " + std::to_string(header.channels) + " channels; 1 or 3 expected");
  }
  CameraImage image;
  image.width = static_cast<int>(header.width);
  image.height = static_cast<int>(header.height);
  image.channels = header.channels;
  image.bits_per_sample = header.bit_depth;
  if (header.significant_bits > 0 && header.significant_bits < header.bit_depth) image.bits_per_sample = header.significant_bits;
  image.pixels.resize(static_cast<size_t>(image.width) * image.height * image.channels);
  if (header.bit_depth == 16) {
    std::memcpy(image.pixels.data(), bytes.data(), image.pixels.size() * sizeof(uint16_t));
  } else {
    std::copy(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(image.pixels.size()), image.pixels.begin());
  }
  return image;
}

}  // namespace svbtdf::common
