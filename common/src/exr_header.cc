#include "exr_header.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "png_reader.h"
#include "svbtdf/common/error.h"

namespace svbtdf::common {
namespace {

constexpr std::array<unsigned char, 4> kMagic = {0x76, 0x2f, 0x31, 0x01};
// Bits of the version field (OpenEXR's file layout, "Version Field").
constexpr uint32_t kTiledFlag = 0x200;
constexpr uint32_t kNonImageFlag = 0x800;  // deep data
constexpr uint32_t kMultipartFlag = 0x1000;
constexpr int kMaxNameLength = 255;  // 31 without the long-names flag; the longer bound is lenient
// OpenEXR allocates buffers of whole chunks (a tile, or up to 256 scanlines) from the header's
// claims; 2^24 samples is a 4096 x 4096 tile, or 256 lines of 65536 pixels.
constexpr int64_t kMaxChunkSamples = int64_t{1} << 24;

// What the chunk offset table of one part depends on.
struct PartHeader {
  bool has_data_window = false;
  int64_t width = 0;
  int64_t height = 0;
  int channels = 0;
  double bytes_per_pixel = 0;  // of the decoded data, over all channels, with their subsampling
  int compression = -1;
  bool has_tiles = false;
  int64_t tile_width = 0;
  int64_t tile_height = 0;
  int64_t chunk_count = -1;  // multi-part and deep files state it
};

// Scanlines per chunk for each of OpenEXR's compression methods (NONE, RLE, ZIPS, ZIP, PIZ,
// PXR24, B44, B44A, DWAA, DWAB); an unknown method gets the largest, the most lenient bound
// (OpenEXR refuses it itself).
int64_t LinesPerChunk(int compression) {
  static constexpr std::array<int64_t, 10> kLines = {1, 1, 1, 16, 32, 16, 32, 32, 32, 256};
  return compression >= 0 && compression < static_cast<int>(kLines.size()) ? kLines[compression] : 256;
}

// The most decoded bytes one file byte can become, per compression method, rounded up: RLE's
// runs of 128 in 2 bytes; deflate's limit of 1032:1 for ZIP, ZIPS and PIZ (whose Huffman stage,
// at least 1 bit per 16-bit value with runs of 255, stays under it); PXR24 is deflate over 24-bit
// floats (x 4/3); B44 stores 32 bytes in 14 (3 when flat); DWA's DCT keeps 1 value of 64 in a
// flat block before deflate. A header claiming more pixels than its file could decode to is
// damaged; believing it costs seconds and hundreds of megabytes (a fuzz finding: a 2.4 kB file
// claiming 983041 x 32 floats took 13 s in the checked build).
double MaxCompressionRatio(int compression) {
  static constexpr std::array<double, 10> kRatio = {1, 64, 1032, 1032, 1032, 1376, 11, 11, 66048, 66048};
  return compression >= 0 && compression < static_cast<int>(kRatio.size()) ? kRatio[compression] : 66048;
}

int PixelTypeBytes(int32_t type) { return type == 1 ? 2 : 4; }  // HALF; UINT and FLOAT

int64_t CeilDivide(int64_t a, int64_t b) { return (a + b - 1) / b; }

// Sequential reads over the file with its size known, so that every claim can be compared with
// what is left.
class HeaderCursor {
 public:
  explicit HeaderCursor(const std::filesystem::path& path) : path_(path), in_(path, std::ios::binary) {
    if (!in_) ThrowIoError(path.string(), "cannot be opened");
    in_.seekg(0, std::ios::end);
    size_ = static_cast<int64_t>(in_.tellg());
    in_.seekg(0);
  }

  int64_t Remaining() const { return size_ - position_; }
  int64_t FileSize() const { return size_; }
  const std::filesystem::path& path() const { return path_; }

  void Read(void* out, int64_t count, const char* what) {
    if (count > Remaining()) Fail(std::string("ends inside its header (in ") + what + ")");
    in_.read(static_cast<char*>(out), count);
    if (!in_) ThrowIoError(path_.string(), "cannot be read");
    position_ += count;
  }

  void Skip(int64_t count, const char* what) {
    if (count > Remaining()) Fail(std::string("ends inside its header (in ") + what + ")");
    in_.seekg(count, std::ios::cur);
    position_ += count;
  }

  // Little-endian, as every EXR field is.
  uint32_t ReadU32(const char* what) {
    unsigned char b[4];
    Read(b, 4, what);
    return uint32_t{b[0]} | uint32_t{b[1]} << 8 | uint32_t{b[2]} << 16 | uint32_t{b[3]} << 24;
  }
  int32_t ReadI32(const char* what) { return static_cast<int32_t>(ReadU32(what)); }
  uint8_t ReadU8(const char* what) {
    uint8_t b = 0;
    Read(&b, 1, what);
    return b;
  }

  // A null-terminated name of at most kMaxNameLength characters; empty ends a list.
  std::string ReadName(const char* what) {
    std::string name;
    for (;;) {
      const char c = static_cast<char>(ReadU8(what));
      if (c == '\0') return name;
      if (static_cast<int>(name.size()) == kMaxNameLength) Fail(std::string("has an unterminated ") + what);
      name.push_back(c);
    }
  }

  [[noreturn]] void Fail(const std::string& problem) const {
    ThrowFormatError(path_.string(), "is not a valid OpenEXR file: it " + problem,
                     "the file is damaged or was cut short");
  }

 private:
  std::filesystem::path path_;
  std::ifstream in_;
  int64_t size_ = 0;
  int64_t position_ = 0;
};

// The channel list: (name, pixel type, pLinear, 3 reserved, x sampling, y sampling)... then an
// empty name.
void ReadChannels(HeaderCursor& cursor, int64_t size, PartHeader& part) {
  const int64_t end = cursor.Remaining() - size;
  part.channels = 0;
  part.bytes_per_pixel = 0;
  // To the empty name, as OpenEXR reads it whatever the stated size (a list cut before its empty
  // name had OpenEXR read one byte more than this check: the checked build's fuzzer).
  while (!cursor.ReadName("the channel list").empty()) {
    const int32_t type = cursor.ReadI32("the channel list");
    cursor.Skip(4, "the channel list");
    const int64_t x_sampling = std::max(1, cursor.ReadI32("the channel list"));
    const int64_t y_sampling = std::max(1, cursor.ReadI32("the channel list"));
    part.bytes_per_pixel += static_cast<double>(PixelTypeBytes(type)) / static_cast<double>(x_sampling * y_sampling);
    ++part.channels;
  }
  if (cursor.Remaining() != end) cursor.Fail("has a channel list that does not match its stated size");
}

// A preview is (width, height, width * height RGBA bytes): the pixel count must be the size.
void CheckPreview(HeaderCursor& cursor, int64_t size) {
  if (size < 8) cursor.Fail("has a preview attribute shorter than its own dimensions");
  const int64_t width = cursor.ReadU32("the preview");
  const int64_t height = cursor.ReadU32("the preview");
  // Bounded by division first: two dimensions of up to 2^32 - 1 overflow their product.
  const int64_t pixel_bytes = size - 8;
  const bool bounded = width == 0 || height <= pixel_bytes / 4 / width;
  if (!bounded || width * height * 4 != pixel_bytes) {
    cursor.Fail("has a preview claiming " + std::to_string(width) + " x " + std::to_string(height) +
                " pixels in " + std::to_string(size - 8) + " bytes");
  }
  cursor.Skip(size - 8, "the preview");
}

// A string vector is (length, characters)... filling its size: no element may claim more.
void CheckStringVector(HeaderCursor& cursor, int64_t size) {
  int64_t left = size;
  while (left > 0) {
    if (left < 4) cursor.Fail("has a string vector attribute cut inside an element's length");
    const int64_t length = cursor.ReadI32("a string vector");
    left -= 4;
    if (length < 0 || length > left) cursor.Fail("has a string vector element longer than its attribute");
    cursor.Skip(length, "a string vector");
    left -= length;
  }
}

// The bytes OpenEXR 3.1 reads for a value of a fixed-size type, whatever the attribute's stated
// size (TypedAttribute<T>::readValueFrom); 0 for the types whose stated size it uses.
int64_t FixedValueBytes(const std::string& type) {
  static const std::map<std::string, int64_t> kBytes = {
      {"box2f", 16},   {"box2i", 16}, {"chromaticities", 32}, {"compression", 1}, {"deepImageState", 1},
      {"double", 8},   {"envmap", 1}, {"float", 4},           {"int", 4},         {"keycode", 28},
      {"lineOrder", 1}, {"m33d", 72}, {"m33f", 36},           {"m44d", 128},      {"m44f", 64},
      {"rational", 8}, {"tiledesc", 9}, {"timecode", 8},      {"v2d", 16},        {"v2f", 8},
      {"v2i", 8},      {"v3d", 24},   {"v3f", 12},            {"v3i", 12}};
  const auto found = kBytes.find(type);
  return found == kBytes.end() ? 0 : found->second;
}

// OpenEXR reads a known type's value its own way: a stated size that differs from what it reads
// would leave this check and OpenEXR reading the rest of the header at different places (the
// checked build's fuzzer: a lineOrder of 257 bytes, after which OpenEXR took later bytes for a
// string attribute claiming 442 MB). Returns the bytes OpenEXR reads.
int64_t BytesOpenExrReads(HeaderCursor& cursor, const std::string& name, const std::string& type, int64_t size) {
  const std::string attribute = "a '" + type + "' attribute '" + name + "' of " + std::to_string(size) + " bytes";
  if (const int64_t fixed = FixedValueBytes(type); fixed > 0 && size != fixed) {
    cursor.Fail("has " + attribute + "; the type holds " + std::to_string(fixed));
  }
  if (type == "floatvector" && size % 4 != 0) cursor.Fail("has " + attribute + ", not a whole number of floats");
  if (type == "idmanifest") {
    // Its 8-byte uncompressed size comes before size - 4 compressed bytes.
    if (size < 4) cursor.Fail("has " + attribute + ", shorter than its own header");
    return size + 4;
  }
  return size;
}

void ReadAttributeValue(HeaderCursor& cursor, const std::string& name, const std::string& type, int64_t size,
                        PartHeader& part) {
  // From here on, a value of a fixed-size type (box2i, compression, ...) has that type's size.
  if (size >= 0) size = BytesOpenExrReads(cursor, name, type, size);
  if (size < 0 || size > cursor.Remaining()) {
    cursor.Fail("has an attribute '" + name + "' claiming " + std::to_string(size) + " bytes with " +
                std::to_string(cursor.Remaining()) + " left in the file");
  }
  if (name == "dataWindow" && type == "box2i") {
    const int64_t x_min = cursor.ReadI32("the data window");
    const int64_t y_min = cursor.ReadI32("the data window");
    const int64_t x_max = cursor.ReadI32("the data window");
    const int64_t y_max = cursor.ReadI32("the data window");
    part.has_data_window = true;
    part.width = x_max - x_min + 1;
    part.height = y_max - y_min + 1;
  } else if (name == "compression" && type == "compression") {
    part.compression = cursor.ReadU8("the compression");
  } else if (name == "tiles" && type == "tiledesc") {
    part.has_tiles = true;
    part.tile_width = cursor.ReadU32("the tile description");
    part.tile_height = cursor.ReadU32("the tile description");
    cursor.Skip(1, "the tile description");
  } else if (name == "chunkCount" && type == "int") {
    part.chunk_count = cursor.ReadI32("the chunk count");
  } else if (type == "chlist") {
    ReadChannels(cursor, size, part);
  } else if (type == "preview") {
    CheckPreview(cursor, size);
  } else if (type == "stringvector") {
    CheckStringVector(cursor, size);
  } else {
    cursor.Skip(size, "an attribute's value");
  }
}

// One header: attributes until an empty name. Returns false for the empty header that ends a
// multi-part file's list.
bool ReadPartHeader(HeaderCursor& cursor, PartHeader& part) {
  bool any = false;
  for (;;) {
    const std::string name = cursor.ReadName("an attribute name");
    if (name.empty()) return any;
    any = true;
    const std::string type = cursor.ReadName("an attribute type");
    ReadAttributeValue(cursor, name, type, cursor.ReadI32("an attribute size"), part);
  }
}

// The least number of chunk offsets the part's table holds (its stated count, or the scanline
// chunks or first-level tiles of its data window), after checking the sizes OpenEXR allocates
// from: the image, and one chunk's buffer.
int64_t LeastChunkCount(HeaderCursor& cursor, const PartHeader& part) {
  if (!part.has_data_window) cursor.Fail("has no data window");
  if (part.width <= 0 || part.height <= 0) {
    cursor.Fail("has an empty or inverted data window (" + std::to_string(part.width) + " x " +
                std::to_string(part.height) + ")");
  }
  const int channels = std::max(1, part.channels);
  RequireSaneImageSize(cursor.path(), part.width, part.height, channels);
  if (part.has_tiles && (part.tile_width <= 0 || part.tile_height <= 0)) cursor.Fail("has tiles of zero size");
  // OpenEXR sizes its line buffers for the compression's whole chunk even when the image has
  // fewer lines: a one-row DWAB file gets buffers of 256 rows, several of them at open.
  // Compared by division: a tile may claim 2^32 - 1 pixels on each side.
  const int64_t chunk_width = part.has_tiles ? part.tile_width : part.width;
  const int64_t chunk_rows = part.has_tiles ? part.tile_height : LinesPerChunk(part.compression);
  if (chunk_width > kMaxChunkSamples / chunk_rows / channels) {
    cursor.Fail("has chunks of " + std::to_string(chunk_width) + " x " + std::to_string(chunk_rows) + " pixels of " +
                std::to_string(channels) + " channels, more than svbtdf reads (" + std::to_string(kMaxChunkSamples) +
                " samples)");
  }
  if (part.chunk_count >= 0) return part.chunk_count;
  if (part.has_tiles) return CeilDivide(part.width, part.tile_width) * CeilDivide(part.height, part.tile_height);
  return CeilDivide(part.height, LinesPerChunk(part.compression));
}

// The pixels a part claims must fit in what the whole file can decode to (MaxCompressionRatio).
// Deep parts state their sample counts in the chunks, not the header, and are left to OpenEXR.
void RequireDecodableFromFile(HeaderCursor& cursor, const PartHeader& part, bool deep) {
  if (deep || !part.has_data_window || part.width <= 0 || part.height <= 0) return;
  const double claimed = static_cast<double>(part.width) * static_cast<double>(part.height) * part.bytes_per_pixel;
  const double ratio = MaxCompressionRatio(part.compression);
  if (claimed > ratio * static_cast<double>(cursor.FileSize())) {
    cursor.Fail("claims " + std::to_string(part.width) + " x " + std::to_string(part.height) + " pixels (" +
                std::to_string(static_cast<int64_t>(claimed)) + " bytes), more than its " +
                std::to_string(cursor.FileSize()) + " bytes can decode to (at most " +
                std::to_string(static_cast<int64_t>(ratio)) + " to 1 with its compression)");
  }
}

}  // namespace

bool HasExrMagic(std::string_view bytes) {
  return bytes.size() >= kMagic.size() && std::memcmp(bytes.data(), kMagic.data(), kMagic.size()) == 0;
}

void RequirePlausibleExrHeaders(const std::filesystem::path& path) {
  HeaderCursor cursor(path);
  char magic[4];
  cursor.Read(magic, 4, "the magic number");
  if (!HasExrMagic(std::string_view(magic, 4))) cursor.Fail("does not begin with OpenEXR's magic number");
  const uint32_t version = cursor.ReadU32("the version field");
  const bool multipart = (version & kMultipartFlag) != 0;
  const bool tiled = (version & kTiledFlag) != 0;
  const bool deep = (version & kNonImageFlag) != 0;

  std::vector<PartHeader> parts;
  for (;;) {
    PartHeader part;
    if (!ReadPartHeader(cursor, part)) break;
    if (tiled && !multipart && !part.has_tiles) cursor.Fail("is marked tiled but has no tile description");
    if ((multipart || deep) && part.chunk_count < 0) cursor.Fail("has a part without a chunk count");
    parts.push_back(part);
    if (!multipart) break;
  }
  if (parts.empty()) cursor.Fail("has no header");

  int64_t offsets = 0;
  for (const PartHeader& part : parts) {
    offsets += LeastChunkCount(cursor, part);
    if (offsets * 8 > cursor.Remaining()) {
      cursor.Fail("claims " + std::to_string(offsets) + " chunks, whose offset table alone needs " +
                  std::to_string(offsets * 8) + " bytes, with " + std::to_string(cursor.Remaining()) + " left");
    }
    RequireDecodableFromFile(cursor, part, deep);
  }
}

}  // namespace svbtdf::common
