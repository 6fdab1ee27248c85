// V4L2 driver logic against the scripted fake driver (fake_v4l2_device.h), plus one smoke test
// against a real /dev/video* device when one is present.

#include <gtest/gtest.h>

#include <algorithm>
#include <memory>

#include "fake_v4l2_device.h"
#include "svbtdf/acquire/v4l2_camera.h"
#include "expect_error.h"
#include "svbtdf/common/error.h"
#include "test_jpeg.h"

namespace svbtdf::acquire {
namespace {

using testing::FakeV4l2Device;

std::shared_ptr<FakeV4l2Device> FakeWithFormats(std::vector<testing::FakeFormat> formats) {
  auto fake = std::make_shared<FakeV4l2Device>();
  fake->Node().formats = std::move(formats);
  return fake;
}

using svbtdf::testing::ExpectError;

void ExpectNoLeak(const FakeV4l2Device& fake) {
  EXPECT_TRUE(fake.open_fds.empty()) << "file descriptor left open";
  EXPECT_TRUE(fake.mapped.empty()) << fake.mapped.size() << " buffers left mapped";
}

TEST(V4l2NegotiationTest, PrefersRawBayerWithMostBitsAndLargestSize) {
  auto fake = FakeWithFormats({{V4L2_PIX_FMT_MJPEG, {{1920, 1080}}},
                               {V4L2_PIX_FMT_YUYV, {{640, 480}}},
                               {V4L2_PIX_FMT_SRGGB8, {{64, 32}}},
                               {V4L2_PIX_FMT_SGRBG10, {{32, 16}, {64, 32}, {48, 24}}},
                               {V4L2_PIX_FMT_GREY, {{64, 32}}}});
  V4l2Camera camera(fake, "/dev/video0");
  EXPECT_EQ(camera.format().fourcc, static_cast<uint32_t>(V4L2_PIX_FMT_SGRBG10));
  EXPECT_EQ(camera.format().width, 64);
  EXPECT_EQ(camera.format().height, 32);
  const Frame frame = camera.Capture();
  EXPECT_EQ(frame.width, 64);
  EXPECT_EQ(frame.channels, 1);
  EXPECT_EQ(frame.bits_per_sample, 10);
  EXPECT_EQ(frame.bayer_pattern, "GRBG");
  EXPECT_TRUE(frame.linear);
  EXPECT_EQ(frame.pixels[0], 100);  // the fake's default exposure, stored as the sample value
}

TEST(V4l2NegotiationTest, FallsBackInPreferenceOrder) {
  struct Case {
    std::vector<uint32_t> offered;
    uint32_t expected;
  };
  const Case cases[] = {
      {{V4L2_PIX_FMT_MJPEG, V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_Y16}, V4L2_PIX_FMT_Y16},
      {{V4L2_PIX_FMT_MJPEG, V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_GREY}, V4L2_PIX_FMT_GREY},
      {{V4L2_PIX_FMT_MJPEG, V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_RGB24}, V4L2_PIX_FMT_RGB24},
      {{V4L2_PIX_FMT_NV12, V4L2_PIX_FMT_MJPEG, V4L2_PIX_FMT_YUYV}, V4L2_PIX_FMT_YUYV},
      {{V4L2_PIX_FMT_NV12, V4L2_PIX_FMT_MJPEG}, V4L2_PIX_FMT_MJPEG},
  };
  for (const Case& test : cases) {
    std::vector<testing::FakeFormat> formats;
    for (uint32_t fourcc : test.offered) formats.push_back({fourcc, {{16, 8}}});
    auto fake = FakeWithFormats(formats);
    fake->jpeg_payload = testing::EncodeTestJpeg(16, 8);
    V4l2Camera camera(fake, "/dev/video0");
    EXPECT_EQ(FourccToString(camera.format().fourcc), FourccToString(test.expected));
    const Frame frame = camera.Capture();
    const bool tone_mapped = test.expected == V4L2_PIX_FMT_YUYV || test.expected == V4L2_PIX_FMT_MJPEG;
    EXPECT_EQ(frame.linear, !tone_mapped) << FourccToString(test.expected);
    EXPECT_EQ(frame.width, 16);
    EXPECT_EQ(frame.height, 8);
  }
}

TEST(V4l2NegotiationTest, MjpegFramesAreDecoded) {
  auto fake = FakeWithFormats({{V4L2_PIX_FMT_MJPEG, {{32, 16}}}});
  fake->jpeg_payload = testing::EncodeTestJpeg(32, 16);
  V4l2Camera camera(fake, "/dev/video0");
  const Frame frame = camera.Capture();
  ASSERT_EQ(frame.channels, 3);
  EXPECT_FALSE(frame.linear);
  // The red channel ramps 0 -> 255 across the width in steps of 8.2; 4:2:0 chroma subsampling
  // averages column pairs, so the ends sit within about one step of the truth.
  EXPECT_NEAR(frame.pixels[0], 0, 10);
  EXPECT_NEAR(frame.pixels[3 * 31], 255, 10);
  EXPECT_NEAR(frame.pixels[3 * (15 * 32) + 1], 255, 10);  // green ramps down the rows
  EXPECT_NEAR(frame.pixels[3 * 16], 255.0 * 16 / 31, 10);
}

TEST(V4l2NegotiationTest, HonoursAnExplicitFormatAndRejectsAMissingOne) {
  auto fake = FakeWithFormats({{V4L2_PIX_FMT_SRGGB12, {{16, 8}}}, {V4L2_PIX_FMT_YUYV, {{16, 8}}}});
  V4l2Options options;
  options.fourcc = "YUYV";
  V4l2Camera camera(fake, "/dev/video0", options);
  EXPECT_EQ(camera.format().fourcc, static_cast<uint32_t>(V4L2_PIX_FMT_YUYV));
  options.fourcc = "RGB3";
  ExpectError(common::ErrorKind::kHardware, "does not offer format RGB3",
              [&] { V4l2Camera other(fake, "/dev/video0", options); });
}

TEST(V4l2NegotiationTest, RejectsDevicesWithoutCaptureOrDecodableFormats) {
  auto output_only = std::make_shared<FakeV4l2Device>();
  output_only->Node().device_caps = V4L2_CAP_VIDEO_OUTPUT | V4L2_CAP_STREAMING;
  ExpectError(common::ErrorKind::kHardware, "not a single-planar video capture device",
              [&] { V4l2Camera camera(output_only, "/dev/video0"); });
  ExpectNoLeak(*output_only);

  auto no_streaming = std::make_shared<FakeV4l2Device>();
  no_streaming->Node().device_caps = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_READWRITE;
  ExpectError(common::ErrorKind::kHardware, "streaming", [&] { V4l2Camera camera(no_streaming, "/dev/video0"); });

  auto undecodable = FakeWithFormats({{V4L2_PIX_FMT_NV12, {{16, 8}}}});
  ExpectError(common::ErrorKind::kHardware, "NV12", [&] { V4l2Camera camera(undecodable, "/dev/video0"); });
  ExpectNoLeak(*undecodable);
}

TEST(V4l2DiscoveryTest, ListsCaptureDevicesAndExplainsUnopenableOnes) {
  FakeV4l2Device fake;
  fake.nodes["/dev/video1"] = fake.nodes["/dev/video0"];
  fake.nodes["/dev/video1"].device_caps = V4L2_CAP_META_CAPTURE | V4L2_CAP_STREAMING;  // UVC metadata node
  fake.nodes["/dev/video2"] = fake.nodes["/dev/video0"];
  fake.nodes["/dev/video2"].open_error = EBUSY;
  const std::vector<CameraInfo> cameras = ListV4l2Cameras(fake);
  ASSERT_EQ(cameras.size(), 2u);
  EXPECT_EQ(cameras[0].id, "v4l2:/dev/video0");
  EXPECT_EQ(cameras[0].model, "Fake Camera");
  EXPECT_EQ(cameras[0].formats, std::vector<std::string>{"RG12 8x4"});
  EXPECT_DOUBLE_EQ(cameras[0].min_exposure_s, 100e-6);
  EXPECT_DOUBLE_EQ(cameras[0].max_exposure_s, 0.5);
  const bool lists_exposure = std::any_of(cameras[0].controls.begin(), cameras[0].controls.end(), [](const std::string& c) {
    return c == "exposure_time,_absolute [1, 5000] 100us";
  });
  EXPECT_TRUE(lists_exposure);
  EXPECT_EQ(cameras[1].id, "v4l2:/dev/video2");
  EXPECT_NE(cameras[1].model.find("busy"), std::string::npos) << cameras[1].model;
  EXPECT_TRUE(fake.open_fds.empty());
}

TEST(V4l2ControlTest, ManualExposureSequenceAndReadBack) {
  auto fake = std::make_shared<FakeV4l2Device>();
  fake->Node().controls[V4L2_CID_AUTOGAIN] = {0, 1, 1, 1, 1, V4L2_CTRL_TYPE_BOOLEAN, "Gain, Automatic"};
  V4l2Camera camera(fake, "/dev/video0");
  fake->log.clear();
  camera.SetExposure({0.0123, 1.0});
  std::vector<std::string> writes;
  for (const auto& entry : fake->log) {
    if (entry.rfind("S_CTRL", 0) == 0) writes.push_back(entry);
  }
  const std::vector<std::string> expected = {
      "S_CTRL:" + std::to_string(V4L2_CID_EXPOSURE_AUTO) + "=" + std::to_string(V4L2_EXPOSURE_MANUAL),
      "S_CTRL:" + std::to_string(V4L2_CID_AUTOGAIN) + "=0",
      "S_CTRL:" + std::to_string(V4L2_CID_EXPOSURE_ABSOLUTE) + "=123",
      "S_CTRL:" + std::to_string(V4L2_CID_GAIN) + "=16"};  // base gain: the control's minimum
  EXPECT_EQ(writes, expected);
  const Frame frame = camera.Capture();
  EXPECT_DOUBLE_EQ(frame.exposure_s, 0.0123);
  EXPECT_EQ(frame.pixels[0], 123);

  // A repeated identical setting writes nothing and discards nothing.
  fake->log.clear();
  const int produced = fake->frames_produced;
  camera.SetExposure({0.0123, 1.0});
  camera.Capture();
  EXPECT_EQ(std::count_if(fake->log.begin(), fake->log.end(),
                          [](const std::string& e) { return e.rfind("S_CTRL", 0) == 0; }), 0);
  EXPECT_EQ(fake->frames_produced, produced + 1);
}

TEST(V4l2ControlTest, ReportsTheExposureTheDriverActuallySet) {
  auto fake = std::make_shared<FakeV4l2Device>();
  fake->exposure_rounding = 8;  // the "driver" rounds 123 down to 120
  V4l2Camera camera(fake, "/dev/video0");
  camera.SetExposure({0.0123, 1.0});
  const Frame frame = camera.Capture();
  EXPECT_DOUBLE_EQ(frame.exposure_s, 0.0120);
  EXPECT_EQ(frame.pixels[0], 120);
}

TEST(V4l2ControlTest, RangeCheckingAgainstQueryctrl) {
  auto fake = std::make_shared<FakeV4l2Device>();
  fake->Node().controls[V4L2_CID_EXPOSURE_ABSOLUTE].step = 10;
  fake->Node().controls[V4L2_CID_EXPOSURE_ABSOLUTE].minimum = 5;
  V4l2Options options;
  V4l2Camera camera(fake, "/dev/video0", options);
  fake->log.clear();
  ExpectError(common::ErrorKind::kInvalidInput, "outside the camera's range", [&] { camera.SetExposure({0.6, 1.0}); });
  ExpectError(common::ErrorKind::kInvalidInput, "outside the camera's range", [&] { camera.SetExposure({1e-5, 1.0}); });
  ExpectError(common::ErrorKind::kInvalidInput, "gain units", [&] { camera.SetExposure({0.01, 2.0}); });
  ExpectError(common::ErrorKind::kInvalidInput, "positive", [&] { camera.SetExposure({-1.0, 1.0}); });
  EXPECT_TRUE(fake->log.empty()) << "rejected settings must not touch the device";
  camera.SetExposure({0.0123, 1.0});  // 123 units snaps to the step grid 5, 15, ..., 125
  EXPECT_EQ(fake->Control(V4L2_CID_EXPOSURE_ABSOLUTE), 125);

  options.gain_units_per_unity = 16.0;
  V4l2Camera scaled(FakeWithFormats({{V4L2_PIX_FMT_GREY, {{8, 4}}}}), "/dev/video0", options);
  scaled.SetExposure({0.01, 2.0});
  EXPECT_DOUBLE_EQ(scaled.Capture().gain, 2.0);
  ExpectError(common::ErrorKind::kInvalidInput, "gain 20", [&] { scaled.SetExposure({0.01, 20.0}); });
}

TEST(V4l2ControlTest, CameraWithoutAbsoluteExposureFailsClearly) {
  auto fake = std::make_shared<FakeV4l2Device>();
  fake->Node().controls.erase(V4L2_CID_EXPOSURE_ABSOLUTE);
  V4l2Camera camera(fake, "/dev/video0");
  ExpectError(common::ErrorKind::kHardware, "V4L2_CID_EXPOSURE_ABSOLUTE", [&] { camera.SetExposure({0.01, 1.0}); });
}

TEST(V4l2DiscardTest, FramesAfterAnExposureChangeCarryTheNewExposure) {
  for (int latency : {0, 1, 2, 3}) {
    auto fake = std::make_shared<FakeV4l2Device>();
    fake->exposure_latency_frames = latency;
    V4l2Options options;
    options.exposure_latency_frames = latency;
    V4l2Camera camera(fake, "/dev/video0", options);
    camera.Capture();  // streaming at the default exposure (100 units)
    for (int units : {300, 20, 4000}) {
      camera.SetExposure({units * 100e-6, 1.0});
      EXPECT_EQ(camera.Capture().pixels[0], units) << "latency " << latency;
      EXPECT_EQ(camera.Capture().pixels[0], units);
    }
  }
}

TEST(V4l2DiscardTest, TheFakeReallyDeliversStaleFramesWithoutDiscarding) {
  // Guards the test above: with the driver's latency set too low, stale frames do come out.
  auto fake = std::make_shared<FakeV4l2Device>();
  fake->exposure_latency_frames = 2;
  V4l2Options options;
  options.exposure_latency_frames = 0;
  V4l2Camera camera(fake, "/dev/video0", options);
  camera.Capture();
  camera.SetExposure({0.03, 1.0});
  EXPECT_EQ(camera.Capture().pixels[0], 100);  // still the old exposure
}

TEST(V4l2DiscardTest, NonMonotonicTimestampsFallBackToCountingFrames) {
  auto fake = std::make_shared<FakeV4l2Device>();
  fake->monotonic_timestamps = false;
  fake->exposure_latency_frames = 2;
  V4l2Camera camera(fake, "/dev/video0");
  camera.Capture();
  const int dequeued = fake->frames_dequeued;
  camera.SetExposure({0.03, 1.0});
  EXPECT_EQ(camera.Capture().pixels[0], 300);
  // buffer_count (4) + latency (2) frames dropped, the next one returned.
  EXPECT_EQ(fake->frames_dequeued - dequeued, 4 + 2 + 1);
}

TEST(V4l2BufferTest, EveryBufferIsRequeuedAndReleasedOnDestruction) {
  auto fake = std::make_shared<FakeV4l2Device>();
  {
    V4l2Camera camera(fake, "/dev/video0");
    EXPECT_EQ(fake->mapped.size(), 4u);
    for (int i = 0; i < 25; ++i) {
      camera.Capture();
      // The driver again holds every buffer: nothing is kept by the camera between captures.
      EXPECT_EQ(fake->queued_indices.size(), 4u);
    }
    EXPECT_EQ(fake->double_queue_errors, 0);
    fake->log.clear();
  }
  const std::vector<std::string> teardown = {"STREAMOFF", "REQBUFS:0"};
  EXPECT_EQ(fake->log, teardown);  // munmap happens between them (REQBUFS(0) fails while mapped)
  ExpectNoLeak(*fake);
}

TEST(V4l2BufferTest, DamagedAndShortFramesAreSkippedOrReportedAndRequeued) {
  auto fake = std::make_shared<FakeV4l2Device>();
  fake->damaged_frames = {0, 1};
  V4l2Camera camera(fake, "/dev/video0");
  EXPECT_EQ(camera.Capture().pixels.size(), 8u * 4u);
  EXPECT_EQ(fake->frames_dequeued, 3);  // two flagged frames dropped
  EXPECT_EQ(fake->queued_indices.size(), 4u);

  auto mjpeg = FakeWithFormats({{V4L2_PIX_FMT_MJPEG, {{16, 8}}}});
  mjpeg->jpeg_payload = testing::EncodeTestJpeg(16, 8);
  mjpeg->jpeg_payload.resize(mjpeg->jpeg_payload.size() / 3);  // truncated transfer
  V4l2Camera broken(mjpeg, "/dev/video0");
  ExpectError(common::ErrorKind::kHardware, "JPEG", [&] { broken.Capture(); });
  EXPECT_EQ(mjpeg->queued_indices.size(), 4u) << "the buffer must go back after a decode failure";
}

TEST(V4l2ErrorTest, UnplugMidStreamGivesHardwareErrorsAndNoLeak) {
  auto fake = std::make_shared<FakeV4l2Device>();
  fake->unplug_after_frames = 3;
  {
    V4l2Camera camera(fake, "/dev/video0");
    for (int i = 0; i < 3; ++i) camera.Capture();
    ExpectError(common::ErrorKind::kHardware, "/dev/video0: VIDIOC_DQBUF failed: No such device",
                [&] { camera.Capture(); });
    ExpectError(common::ErrorKind::kHardware, "reconnect", [&] { camera.Capture(); });
    ExpectError(common::ErrorKind::kHardware, "No such device", [&] { camera.SetExposure({0.02, 1.0}); });
  }
  ExpectNoLeak(*fake);
}

TEST(V4l2ErrorTest, TimeoutIsAHardwareErrorAndTheCameraRecovers) {
  auto fake = std::make_shared<FakeV4l2Device>();
  V4l2Options options;
  options.frame_timeout_s = 0.5;
  {
    V4l2Camera camera(fake, "/dev/video0", options);
    fake->stall = true;
    ExpectError(common::ErrorKind::kHardware, "no frame within", [&] { camera.Capture(); });
    fake->stall = false;  // a stalled bus that comes back: the next capture works
    EXPECT_EQ(camera.Capture().pixels[0], 100);
  }
  ExpectNoLeak(*fake);
}

TEST(V4l2ErrorTest, SetupFailuresNameTheCallAndReleaseEverything) {
  {
    auto fake = std::make_shared<FakeV4l2Device>();
    fake->Node().open_error = EBUSY;
    ExpectError(common::ErrorKind::kHardware, "open failed: Device or resource busy",
                [&] { V4l2Camera camera(fake, "/dev/video0"); });
  }
  for (unsigned long call : {VIDIOC_S_FMT, VIDIOC_REQBUFS, VIDIOC_STREAMON, VIDIOC_QBUF}) {
    auto fake = std::make_shared<FakeV4l2Device>();
    fake->fail_ioctl[call] = EIO;
    ExpectError(common::ErrorKind::kHardware, "VIDIOC_" + testing::IoctlName(call) + " failed: Input/output error",
                [&] { V4l2Camera camera(fake, "/dev/video0"); });
    ExpectNoLeak(*fake);
  }
  auto fake = std::make_shared<FakeV4l2Device>();
  fake->fail_mmap_at_index = 2;
  ExpectError(common::ErrorKind::kHardware, "mmap failed", [&] { V4l2Camera camera(fake, "/dev/video0"); });
  ExpectNoLeak(*fake);  // buffers 0 and 1 were mapped and must be unmapped again
}

TEST(V4l2RealDeviceTest, CapturesOneFrameFromAConnectedCamera) {
  std::string path;
  for (const CameraInfo& info : ListV4l2Cameras()) {
    if (info.model.rfind("(cannot open", 0) != 0) {
      path = info.id.substr(5);
      break;
    }
  }
  if (path.empty()) GTEST_SKIP() << "no openable V4L2 capture device on this machine";
  auto camera = OpenV4l2Camera(path);
  const Frame frame = camera->Capture();
  EXPECT_GT(frame.width, 0);
  EXPECT_EQ(frame.pixels.size(), static_cast<size_t>(frame.width) * frame.height * frame.channels);
}

}  // namespace
}  // namespace svbtdf::acquire
