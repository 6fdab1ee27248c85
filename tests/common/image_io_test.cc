// Round trips and error reporting of the image files users hand in and get back.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <vector>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/image_io.h"
#include "temp_folder.h"

namespace svbtdf::common {
namespace {
namespace fs = std::filesystem;

class ImageIo : public ::testing::Test {
 protected:
  svbtdf::testing::TempFolder folder_;
  const fs::path dir_ = folder_.path();
};

void ExpectErrorNaming(const std::function<void()>& f, const fs::path& file) {
  try {
    f();
    FAIL() << "expected an error naming " << file;
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
  }
}

TEST_F(ImageIo, SixteenBitCameraImagesRoundTripExactly) {
  CameraImage image;
  image.width = 7;
  image.height = 5;
  image.channels = 3;
  image.bits_per_sample = 12;
  for (int k = 0; k < 7 * 5 * 3; ++k) image.pixels.push_back(static_cast<uint16_t>((k * 977) % 4096));
  const fs::path png = dir_ / "frame.png";
  WriteCameraImage(png, image);
  const CameraImage read = ReadCameraImage(png);
  EXPECT_EQ(read.width, 7);
  EXPECT_EQ(read.height, 5);
  EXPECT_EQ(read.channels, 3);
  EXPECT_EQ(read.pixels, image.pixels);
  // Never overwrites a capture by default.
  EXPECT_THROW(WriteCameraImage(png, image), Error);
}

TEST_F(ImageIo, ExrMapsRoundTripWithinHalfPrecision) {
  FloatImage map(4, 3, 3);
  for (size_t k = 0; k < map.pixels.size(); ++k) map.pixels[k] = 0.001f * static_cast<float>(k * k) + 0.5f;
  WriteFloatImage(dir_ / "k_s.exr", map);
  WriteFloatImage(dir_ / "alpha.exr", map, /*half_precision=*/false);
  const FloatImage half = ReadFloatImage(dir_ / "k_s.exr");
  const FloatImage full = ReadFloatImage(dir_ / "alpha.exr");
  ASSERT_EQ(half.pixels.size(), map.pixels.size());
  for (size_t k = 0; k < map.pixels.size(); ++k) {
    EXPECT_NEAR(half.pixels[k], map.pixels[k], 1e-3 * map.pixels[k]);
    EXPECT_EQ(full.pixels[k], map.pixels[k]);
  }
}

TEST_F(ImageIo, BrokenFilesGetErrorsNamingThem) {
  const fs::path missing = dir_ / "missing.png";
  ExpectErrorNaming([&] { ReadCameraImage(missing); }, missing);
  const fs::path garbage = dir_ / "garbage.png";
  WriteTextAtomically(garbage, "this is not a PNG at all");
  ExpectErrorNaming([&] { ReadCameraImage(garbage); }, garbage);
  // A truncated PNG: a valid file cut in half.
  CameraImage image;
  image.width = image.height = 64;
  image.pixels.assign(64 * 64, 1234);
  for (size_t k = 0; k < image.pixels.size(); ++k) image.pixels[k] = static_cast<uint16_t>(k * 31);
  const fs::path whole = dir_ / "whole.png", cut = dir_ / "cut.png";
  WriteCameraImage(whole, image);
  const std::string bytes = ReadTextFile(whole);
  WriteTextAtomically(cut, bytes.substr(0, bytes.size() / 2));
  ExpectErrorNaming([&] { ReadCameraImage(cut); }, cut);
  // A float map where camera values are expected.
  WriteFloatImage(dir_ / "map.exr", FloatImage(2, 2, 1, 0.5f));
  ExpectErrorNaming([&] { ReadCameraImage(dir_ / "map.exr"); }, dir_ / "map.exr");
}

// A symlink loop in place of an image: stat fails with ELOOP, which must be said as what it is
// (and not thrown as std::filesystem_error, an "internal error" naming nothing), by both readers.
TEST_F(ImageIo, ASymlinkLoopIsReportedAsOneLineNamingIt) {
  for (const char* name : {"loop.png", "loop.exr"}) {
    const fs::path loop = dir_ / name;
    fs::create_symlink(loop, loop);
    const auto read = [&] { std::string(name).ends_with(".png") ? (void)ReadCameraImage(loop) : (void)ReadFloatImage(loop); };
    ExpectErrorNaming(read, loop);
    try {
      read();
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("symbolic links"), std::string::npos) << e.what();
    }
  }
}

TEST_F(ImageIo, EightBitPngsReadWithoutRescaling) {
  std::vector<uint8_t> rgb;
  for (int k = 0; k < 5 * 4 * 3; ++k) rgb.push_back(static_cast<uint8_t>(k * 13));
  WriteRgb8Png(dir_ / "picture.png", rgb, 5, 4);
  const CameraImage read = ReadCameraImage(dir_ / "picture.png");
  EXPECT_EQ(read.bits_per_sample, 8);
  ASSERT_EQ(read.pixels.size(), rgb.size());
  for (size_t k = 0; k < rgb.size(); ++k) EXPECT_EQ(read.pixels[k], rgb[k]);
}

// The message of the error ReadCameraImage throws for `path` (empty when it reads).
std::string ReadFailure(const fs::path& path) {
  try {
    ReadCameraImage(path);
  } catch (const Error& e) {
    return e.what();
  }
  return {};
}

// libpng's default error handler prints "libpng error: ..." on stderr; a user must see one line,
// ours, which carries libpng's words.
TEST_F(ImageIo, DamagedPngsAreReportedInOneLineThatSaysWhatLibpngFound) {
  CameraImage image;
  image.width = image.height = 32;
  for (int k = 0; k < 32 * 32; ++k) image.pixels.push_back(static_cast<uint16_t>(k * 7));
  WriteCameraImage(dir_ / "whole.png", image);
  const std::string bytes = ReadTextFile(dir_ / "whole.png");
  std::string bad_chunk = bytes;
  bad_chunk[bad_chunk.find("IDAT") + 1] = '!';  // an invalid chunk type
  WriteTextAtomically(dir_ / "bad_chunk.png", bad_chunk);
  WriteTextAtomically(dir_ / "cut.png", bytes.substr(0, bytes.size() - 40));
  for (const char* name : {"bad_chunk.png", "cut.png"}) {
    ::testing::internal::CaptureStderr();
    const std::string message = ReadFailure(dir_ / name);
    EXPECT_EQ(::testing::internal::GetCapturedStderr(), "") << name;
    EXPECT_NE(message.find((dir_ / name).string()), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
  EXPECT_NE(ReadFailure(dir_ / "bad_chunk.png").find("invalid chunk type"), std::string::npos);
}

TEST_F(ImageIo, NonFiniteValuesAreReportedWithTheirPixel) {
  FloatImage map(3, 2, 1, 1.0f);
  EXPECT_NO_THROW(RequireFinite(map, "rho_d.exr"));
  map.at(2, 1) = std::numeric_limits<float>::quiet_NaN();
  try {
    RequireFinite(map, "rho_d.exr");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("rho_d.exr"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("(2, 1)"), std::string::npos);
  }
}

}  // namespace
}  // namespace svbtdf::common
