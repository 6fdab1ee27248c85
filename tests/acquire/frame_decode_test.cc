// Frame decoding shared by the camera drivers (acquire/src/frame_decode.cc): packed MIPI RAW10
// and RAW12, 16-bit raw with stride and masked bits, YUYV and BGR.

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "svbtdf/acquire/frame_decode.h"
#include "svbtdf/common/error.h"

namespace svbtdf::acquire {
namespace {

TEST(FrameDecodeTest, UnpacksMipiRaw10And12) {
  // RAW10: samples 0x3FF, 0x000, 0x155, 0x2AA -> MSBs FF 00 55 AA, LSB byte 11 00 01 10 b.
  const uint8_t raw10[] = {0xFF, 0x00, 0x55, 0xAA, 0b10010011};
  const Frame ten = DecodeImage({SampleLayout::kMipiPacked10, 10, "RGGB", "p"}, raw10, 5, 4, 1, 5, "t");
  EXPECT_EQ(ten.pixels, (std::vector<uint16_t>{0x3FF, 0x000, 0x155, 0x2AA}));
  EXPECT_EQ(ten.bits_per_sample, 10);
  // RAW12: samples 0xABC, 0x123 -> AB 12 then LSB nibbles C (low) and 3 (high) = 0x3C.
  const uint8_t raw12[] = {0xAB, 0x12, 0x3C};
  const Frame twelve = DecodeImage({SampleLayout::kMipiPacked12, 12, "", "p"}, raw12, 3, 2, 1, 3, "t");
  EXPECT_EQ(twelve.pixels, (std::vector<uint16_t>{0xABC, 0x123}));
}

TEST(FrameDecodeTest, RespectsStrideAndMasksUnusedBits) {
  // Two rows of two 10-bit samples in 16-bit containers, rows padded to 6 bytes; the padding
  // and the top bits (set to garbage) must not leak into the samples.
  const uint8_t data[] = {0x01, 0xFC, 0x02, 0x00, 0xEE, 0xEE, 0xFF, 0x03, 0x04, 0x00, 0xEE, 0xEE};
  const Frame frame = DecodeImage({SampleLayout::kRaw16, 10, "BGGR", "SBGGR10"}, data, sizeof data, 2, 2, 6, "t");
  EXPECT_EQ(frame.pixels, (std::vector<uint16_t>{0x001, 0x002, 0x3FF, 0x004}));
  try {
    DecodeImage({SampleLayout::kRaw16, 10, "", ""}, data, 9, 2, 2, 6, "cam");
    FAIL() << "a short frame must be rejected";
  } catch (const common::Error& error) {
    EXPECT_EQ(error.kind(), common::ErrorKind::kHardware);
  }
}

TEST(FrameDecodeTest, YuyvLimitedRangeGreysAndBgrOrder) {
  const uint8_t yuyv[] = {16, 128, 235, 128};
  const Frame grey = DecodeImage({SampleLayout::kYuyv, 8, "", "YUYV"}, yuyv, 4, 2, 1, 4, "t");
  EXPECT_EQ(grey.pixels, (std::vector<uint16_t>{0, 0, 0, 255, 255, 255}));
  EXPECT_FALSE(grey.linear);
  const uint8_t bgr[] = {1, 2, 3};
  EXPECT_EQ(DecodeImage({SampleLayout::kBgr24, 8, "", "BGR3"}, bgr, 3, 1, 1, 3, "t").pixels,
            (std::vector<uint16_t>{3, 2, 1}));
}

}  // namespace
}  // namespace svbtdf::acquire
