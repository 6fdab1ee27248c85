#include "svbtdf/common/image_io.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstddef>
#include <fstream>
#include <memory>
#include <vector>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "exr_header.h"
#include "png_reader.h"

namespace svbtdf::common {
namespace fs = std::filesystem;
namespace {

bool HasExtension(const fs::path& path, std::string_view wanted) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(), [](unsigned char c) { return std::tolower(c); });
  return extension == wanted;
}

std::string FirstBytes(const fs::path& path, size_t count) {
  std::ifstream in(path, std::ios::binary);
  std::string bytes(count, '\0');
  in.read(bytes.data(), static_cast<std::streamsize>(count));
  bytes.resize(static_cast<size_t>(std::max<std::streamsize>(0, in.gcount())));
  return bytes;
}

// OpenEXR files are checked against their own size before OpenEXR reads them (exr_header.h),
// and read by OpenEXR alone: OpenImageIO would otherwise hand a damaged .exr to every other
// reader it has in turn (DICOM, FITS, ...), each with its own way of failing.
std::unique_ptr<OIIO::ImageInput> OpenForReading(const fs::path& path) {
  RequireExistingFile(path);
  const bool exr = HasExrMagic(FirstBytes(path, 4));
  if (!exr && HasExtension(path, ".exr")) {
    ThrowFormatError(path.string(), "is named .exr but is not an OpenEXR file (it does not begin with EXR's magic number)",
                     "the file is damaged, or another format was saved under this name");
  }
  if (exr) RequirePlausibleExrHeaders(path);
  std::unique_ptr<OIIO::ImageInput> input =
      exr ? OIIO::ImageInput::create("openexr") : OIIO::ImageInput::open(path.string());
  if (input && exr) {
    OIIO::ImageSpec ignored;
    if (!input->open(path.string(), ignored)) input.reset();
  }
  if (!input) {
    ThrowFormatError(path.string(), "cannot be decoded as an image: " + OIIO::geterror(),
                     "is the file complete and in a format OpenImageIO reads (PNG, TIFF, EXR)?");
  }
  const OIIO::ImageSpec& spec = input->spec();
  RequireSaneImageSize(path, spec.width, spec.height, spec.nchannels);
  return input;
}

bool IsPng(const fs::path& path) { return HasExtension(path, ".png"); }

std::vector<std::string> ChannelNames(int channels) {
  if (channels == 1) return {"Y"};
  if (channels == 3) return {"R", "G", "B"};
  if (channels == 4) return {"R", "G", "B", "A"};
  std::vector<std::string> names;
  for (int c = 0; c < channels; ++c) names.push_back("A" + std::to_string(c));
  return names;
}

// Encodes the image in memory and writes the bytes through WriteBytesAtomically, whose every
// write is checked: OpenImageIO's PNG writer goes through stdio and does not report a full disk,
// so a file it wrote itself could be short or empty and still look written.
void EncodeAndWrite(const fs::path& path, const OIIO::ImageSpec& spec, OIIO::TypeDesc buffer_type, const void* pixels,
                    bool overwrite) {
  // The format is chosen from the path's extension.
  auto output = OIIO::ImageOutput::create(path.string());
  if (!output) ThrowIoError(path.string(), "no image writer for this extension: " + OIIO::geterror());
  if (!output->supports("ioproxy")) {
    ThrowInvalidInput(path.string(), std::string("cannot be written: the ") + output->format_name() +
                                         " writer cannot encode to memory", "write PNG or EXR");
  }
  std::vector<unsigned char> encoded;
  OIIO::Filesystem::IOVecOutput memory(encoded);
  if (!output->set_ioproxy(&memory) || !output->open(path.string(), spec) ||
      !output->write_image(buffer_type, pixels) || !output->close()) {
    ThrowIoError(path.string(), "cannot encode: " + output->geterror());
  }
  WriteBytesAtomically(path, std::string_view(reinterpret_cast<const char*>(encoded.data()), encoded.size()),
                       overwrite);
}

// Converts `rows` scanlines of `spec`'s native layout (every channel in its own type when the
// file mixes them) to interleaved floats.
bool ConvertToFloat(const OIIO::ImageSpec& spec, int rows, const std::byte* native, float* out) {
  if (spec.channelformats.empty()) {
    return OIIO::convert_pixel_values(spec.format, native, OIIO::TypeDesc::FLOAT, out,
                                      static_cast<int>(static_cast<size_t>(rows) * spec.width * spec.nchannels));
  }
  const auto native_pixel_bytes = static_cast<OIIO::stride_t>(spec.pixel_bytes(/*native=*/true));
  const auto float_pixel_bytes = static_cast<OIIO::stride_t>(sizeof(float) * spec.nchannels);
  size_t offset = 0;
  for (int c = 0; c < spec.nchannels; ++c) {
    const OIIO::TypeDesc type = spec.channelformats[c];
    if (!OIIO::convert_image(1, spec.width, rows, 1, native + offset, type, native_pixel_bytes, OIIO::AutoStride,
                             OIIO::AutoStride, out + c, OIIO::TypeDesc::FLOAT, float_pixel_bytes, OIIO::AutoStride,
                             OIIO::AutoStride)) {
      return false;
    }
    offset += type.size();
  }
  return true;
}

}  // namespace

CameraImage ReadCameraImage(const fs::path& path) {
  if (IsPng(path)) return ReadPngCameraImage(path);
  auto input = OpenForReading(path);
  const OIIO::ImageSpec& spec = input->spec();
  if (spec.format.basetype != OIIO::TypeDesc::UINT8 && spec.format.basetype != OIIO::TypeDesc::UINT16) {
    ThrowFormatError(path.string(), "is not an 8- or 16-bit integer image (got " + std::string(spec.format.c_str()) + ")",
                     "camera frames are stored as 16-bit PNG or TIFF");
  }
  const int stored_channels = spec.nchannels;
  const int channels = stored_channels == 4 || stored_channels == 2 ? stored_channels - 1 : stored_channels;
  if (channels != 1 && channels != 3) {
    ThrowFormatError(path.string(), "has " + std::to_string(stored_channels) + " channels; 1 or 3 expected");
  }
  CameraImage image;
  image.width = spec.width;
  image.height = spec.height;
  image.channels = channels;
  image.bits_per_sample = spec.format.basetype == OIIO::TypeDesc::UINT8 ? 8 : 16;
  const int stored_bits = spec.get_int_attribute("oiio:BitsPerSample", image.bits_per_sample);
  if (stored_bits > 0 && stored_bits < image.bits_per_sample) image.bits_per_sample = stored_bits;
  image.pixels.resize(static_cast<size_t>(spec.width) * spec.height * channels);
  // Read in the file's own type so that values are not rescaled, then widen to 16 bits.
  if (spec.format.basetype == OIIO::TypeDesc::UINT8) {
    std::vector<uint8_t> narrow(image.pixels.size());
    if (!input->read_image(0, 0, 0, channels, OIIO::TypeDesc::UINT8, narrow.data())) {
      ThrowFormatError(path.string(), "is truncated or corrupt: " + input->geterror());
    }
    std::copy(narrow.begin(), narrow.end(), image.pixels.begin());
  } else if (!input->read_image(0, 0, 0, channels, OIIO::TypeDesc::UINT16, image.pixels.data())) {
    ThrowFormatError(path.string(), "is truncated or corrupt: " + input->geterror());
  }
  return image;
}

void WriteCameraImage(const fs::path& path, const CameraImage& image, bool overwrite) {
  if (image.channels != 1 && image.channels != 3) ThrowInvalidInput(path.string(), "camera images have 1 or 3 channels");
  if (image.pixels.size() != static_cast<size_t>(image.width) * image.height * image.channels) {
    ThrowInvalidInput(path.string(), "pixel count does not match the image size");
  }
  OIIO::ImageSpec spec(image.width, image.height, image.channels, OIIO::TypeDesc::UINT16);
  spec.channelnames = ChannelNames(image.channels);
  spec.attribute("oiio:BitsPerSample", image.bits_per_sample);
  // Camera noise barely compresses: zlib's fastest level writes a 1280 x 1024 frame about 4x
  // faster than its default for 2% more bytes. And no row filter: libpng's default tries all five
  // on every row, which took half of the remaining time for nothing on noise (a 1280 x 1024
  // board view 0.236 -> 0.123 s and 2.5% smaller; a 24 MP dot image of grid-sheet 0.188 -> 0.095
  // s, 0.1% larger; a dark 240 x 200 dot image 16% larger, 75 -> 87 kB).
  spec.attribute("png:compressionLevel", 1);
  spec.attribute("png:filter", 8);  // PNG_FILTER_NONE
  EncodeAndWrite(path, spec, spec.format, image.pixels.data(), overwrite);
}

void WriteRgb8Png(const fs::path& path, const std::vector<uint8_t>& pixels, int width, int height, bool overwrite) {
  if (pixels.size() != static_cast<size_t>(width) * height * 3) {
    ThrowInvalidInput(path.string(), "pixel count does not match the image size");
  }
  OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
  spec.channelnames = ChannelNames(3);
  EncodeAndWrite(path, spec, spec.format, pixels.data(), overwrite);
}

FloatImage ReadFloatImage(const fs::path& path) {
  auto input = OpenForReading(path);
  const OIIO::ImageSpec& spec = input->spec();
  FloatImage image;
  image.width = spec.width;
  image.height = spec.height;
  image.channels = spec.nchannels;
  // Strip by strip, so that memory follows what has been decoded and not what the header
  // claims: a damaged file fails in its first strip, however large it says it is. 256 rows
  // hold whole chunks for every EXR compression. The strips are read in the file's own types
  // and converted here: asked for floats, OpenImageIO converts through a buffer of at least
  // 256 scanlines whatever the image's height (a fuzz finding: a one-row DWA file 4 kB long
  // whose scanline claims 8.6 MB made it allocate 2.2 GB).
  const size_t row_samples = static_cast<size_t>(spec.width) * spec.nchannels;
  const size_t native_row_bytes = spec.scanline_bytes(/*native=*/true);
  constexpr int kStripRows = 256;
  std::vector<std::byte> native;
  for (int y = 0; y < spec.height; y += kStripRows) {
    const int rows = std::min(kStripRows, spec.height - y);
    native.resize(static_cast<size_t>(rows) * native_row_bytes);
    image.pixels.resize(static_cast<size_t>(y + rows) * row_samples);
    if (!input->read_native_scanlines(0, 0, spec.y + y, spec.y + y + rows, 0, native.data()) ||
        !ConvertToFloat(spec, rows, native.data(), image.pixels.data() + static_cast<size_t>(y) * row_samples)) {
      ThrowFormatError(path.string(), "is truncated or corrupt: " + input->geterror());
    }
  }
  return image;
}

void WriteFloatImage(const fs::path& path, const FloatImage& image, bool half_precision, bool overwrite) {
  if (image.pixels.size() != static_cast<size_t>(image.width) * image.height * image.channels || image.channels < 1) {
    ThrowInvalidInput(path.string(), "pixel count does not match the image size");
  }
  OIIO::ImageSpec spec(image.width, image.height, image.channels,
                       half_precision ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::FLOAT);
  spec.channelnames = ChannelNames(image.channels);
  spec.attribute("compression", "zip");
  // OpenImageIO converts the float buffer to half when the file asks for it.
  EncodeAndWrite(path, spec, OIIO::TypeDesc::FLOAT, image.pixels.data(), overwrite);
}

void RequireFinite(const FloatImage& image, const std::string& source) {
  for (size_t k = 0; k < image.pixels.size(); ++k) {
    if (!std::isfinite(image.pixels[k])) {
      const size_t pixel = k / image.channels;
      ThrowFormatError(source, "holds a non-finite value at pixel (" + std::to_string(pixel % image.width) + ", " +
                                   std::to_string(pixel / image.width) + ")",
                       "the file is corrupt or was written by a broken tool");
    }
  }
}

}  // namespace svbtdf::common
