// libcamera driver logic (request recycling, exposure settling, timeouts, cancellation) against
// a fake LibcameraSession that completes requests on its own thread like libcamera does, plus a
// smoke test of the real CameraManager.

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <thread>

#include "svbtdf/acquire/libcamera_camera.h"
#include "expect_error.h"
#include "svbtdf/common/error.h"

namespace svbtdf::acquire {
namespace {

// Sensor model: a request's controls reach the sensor `pipeline_delay` requests later (the
// metadata reports what the sensor really used), exposure is clamped to `exposure_cap_s`, and
// every sample of a frame holds the exposure used in microseconds / 10 as an 8-bit raw value.
class FakeLibcameraSession : public LibcameraSession {
 public:
  struct Shared {
    std::atomic<int> queue_calls{0}, double_queues{0}, stop_calls{0}, completed{0};
    std::atomic<bool> stall{false}, cancel_next{false}, report_exposure{true};
    std::atomic<int> fail_frames{0};
    double exposure_cap_s = 1.0;
    int pipeline_delay = 2;
  };

  explicit FakeLibcameraSession(std::shared_ptr<Shared> shared) : shared_(std::move(shared)) {
    buffers_.assign(4, std::vector<uint8_t>(8 * 4));
    queued_.assign(4, false);
    worker_ = std::thread([this] { Run(); });
  }
  ~FakeLibcameraSession() override {
    {
      std::lock_guard lock(mutex_);
      quit_ = true;
    }
    wake_.notify_all();
    worker_.join();
  }

  CameraInfo Info() const override {
    CameraInfo info;
    info.id = "libcamera:fake";
    info.model = "Fake Sensor";
    info.formats = {"SRGGB8 8x4"};
    info.min_exposure_s = 1e-5;
    info.max_exposure_s = 1.0;
    return info;
  }
  LibcameraStreamInfo Stream() const override {
    return {{SampleLayout::kRaw8, 8, "RGGB", "SRGGB8"}, 8, 4, 8, 4};
  }
  LibcameraRange ExposureRange() const override { return {true, 1e-5, 1.0}; }
  LibcameraRange GainRange() const override { return {true, 1.0, 16.0}; }
  void SetCompletionHandler(std::function<void(const LibcameraCompletion&)> handler) override {
    std::lock_guard lock(mutex_);
    handler_ = std::move(handler);
  }
  int Start() override { return 0; }
  int Queue(int index, double exposure_s, double gain) override {
    ++shared_->queue_calls;
    std::lock_guard lock(mutex_);
    if (queued_[index]) {
      ++shared_->double_queues;
      return -EINVAL;
    }
    queued_[index] = true;
    pending_.push_back({index, exposure_s, gain});
    wake_.notify_all();
    return 0;
  }
  std::pair<const uint8_t*, size_t> BufferData(int index) const override {
    return {buffers_[index].data(), buffers_[index].size()};
  }
  void Stop() override {
    ++shared_->stop_calls;
    std::unique_lock lock(mutex_);
    // libcamera completes every pending request as cancelled before stop() returns.
    while (!pending_.empty()) {
      const Pending request = pending_.front();
      pending_.pop_front();
      queued_[request.index] = false;
      LibcameraCompletion completion;
      completion.buffer_index = request.index;
      completion.cancelled = true;
      if (handler_) handler_(completion);
    }
  }

 private:
  struct Pending {
    int index;
    double exposure_s, gain;
  };

  void Run() {
    std::unique_lock lock(mutex_);
    for (;;) {
      wake_.wait_for(lock, std::chrono::milliseconds(1));
      if (quit_) return;
      if (pending_.empty() || shared_->stall) continue;
      const Pending request = pending_.front();
      pending_.pop_front();
      history_.push_back(request.exposure_s);
      // The sensor uses the exposure requested pipeline_delay requests ago.
      const long applied = static_cast<long>(history_.size()) - 1 - shared_->pipeline_delay;
      const double used =
          std::min(applied < 0 ? initial_exposure_s_ : history_[applied], shared_->exposure_cap_s);
      std::fill(buffers_[request.index].begin(), buffers_[request.index].end(),
                static_cast<uint8_t>(std::min(255.0, std::round(used * 1e5))));
      queued_[request.index] = false;
      LibcameraCompletion completion;
      completion.buffer_index = request.index;
      completion.cancelled = shared_->cancel_next.exchange(false);
      completion.frame_ok = true;
      if (shared_->fail_frames > 0) {
        --shared_->fail_frames;
        completion.frame_ok = false;
      }
      if (shared_->report_exposure) completion.exposure_s = used;
      completion.gain = request.gain;
      ++shared_->completed;
      if (handler_) handler_(completion);
    }
  }

  std::shared_ptr<Shared> shared_;
  std::vector<std::vector<uint8_t>> buffers_;
  std::vector<bool> queued_;
  std::deque<Pending> pending_;
  std::vector<double> history_;
  double initial_exposure_s_ = 0.0005;
  std::function<void(const LibcameraCompletion&)> handler_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool quit_ = false;
  std::thread worker_;
};

std::unique_ptr<LibcameraCamera> MakeCamera(const std::shared_ptr<FakeLibcameraSession::Shared>& shared,
                                            LibcameraOptions options = {}) {
  options.initial_exposure_s = 0.0005;
  return std::make_unique<LibcameraCamera>(std::make_unique<FakeLibcameraSession>(shared), "fake",
                                           options);
}

using svbtdf::testing::ExpectError;

TEST(LibcameraDriverTest, ExposureChangeSettlesBeforeAFrameIsReturned) {
  for (int delay : {0, 2, 5}) {
    auto shared = std::make_shared<FakeLibcameraSession::Shared>();
    shared->pipeline_delay = delay;
    auto camera = MakeCamera(shared);
    for (double exposure : {0.0012, 0.0005, 0.002}) {
      camera->SetExposure({exposure, 2.0});
      for (int repeat = 0; repeat < 3; ++repeat) {
        const Frame frame = camera->Capture();
        EXPECT_NEAR(frame.exposure_s, exposure, 1e-12) << "delay " << delay;
        EXPECT_EQ(frame.pixels[0], std::lround(exposure * 1e5)) << "pixels exposed the old way";
        EXPECT_DOUBLE_EQ(frame.gain, 2.0);
        EXPECT_EQ(frame.bayer_pattern, "RGGB");
      }
    }
    EXPECT_EQ(shared->double_queues, 0);
  }
}

TEST(LibcameraDriverTest, WithoutMetadataDropsAFixedNumberOfFrames) {
  auto shared = std::make_shared<FakeLibcameraSession::Shared>();
  shared->report_exposure = false;
  shared->pipeline_delay = 3;
  LibcameraOptions options;
  options.fallback_discard_frames = 4;
  auto camera = MakeCamera(shared, options);
  camera->SetExposure({0.0015, 1.0});
  const Frame frame = camera->Capture();
  EXPECT_EQ(frame.pixels[0], 150);
  EXPECT_DOUBLE_EQ(frame.exposure_s, 0.0015);  // the requested value: nothing better is known
}

TEST(LibcameraDriverTest, ExposureTheCameraNeverAppliesIsAHardwareError) {
  auto shared = std::make_shared<FakeLibcameraSession::Shared>();
  shared->exposure_cap_s = 0.001;  // e.g. frame duration limits
  auto camera = MakeCamera(shared);
  camera->SetExposure({0.002, 1.0});
  ExpectError(common::ErrorKind::kHardware, "instead of the requested", [&] { camera->Capture(); });
}

TEST(LibcameraDriverTest, RangeChecksUseTheCameraControls) {
  auto shared = std::make_shared<FakeLibcameraSession::Shared>();
  auto camera = MakeCamera(shared);
  ExpectError(common::ErrorKind::kInvalidInput, "outside", [&] { camera->SetExposure({2.0, 1.0}); });
  ExpectError(common::ErrorKind::kInvalidInput, "analogue gain", [&] { camera->SetExposure({0.01, 32.0}); });
  ExpectError(common::ErrorKind::kInvalidInput, "positive", [&] { camera->SetExposure({0.01, 0.0}); });
}

TEST(LibcameraDriverTest, TimeoutIsAHardwareError) {
  auto shared = std::make_shared<FakeLibcameraSession::Shared>();
  LibcameraOptions options;
  options.frame_timeout_s = 0.2;
  auto camera = MakeCamera(shared, options);
  camera->Capture();
  shared->stall = true;
  // Frames completed before the stall may still be waiting; the capture after them times out.
  double waited = 0.0;
  ExpectError(common::ErrorKind::kHardware, "no request completed within", [&] {
    for (int i = 0; i < 6; ++i) {
      const auto start = std::chrono::steady_clock::now();
      try {
        camera->Capture();
      } catch (...) {
        waited = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        throw;
      }
    }
  });
  EXPECT_GE(waited, 0.2);
  EXPECT_LT(waited, 1.0);
  shared->stall = false;  // the stream resumes and so does capture
  EXPECT_EQ(camera->Capture().width, 8);
}

TEST(LibcameraDriverTest, CancelledRequestMeansTheCameraIsGone) {
  auto shared = std::make_shared<FakeLibcameraSession::Shared>();
  auto camera = MakeCamera(shared);
  camera->Capture();
  shared->cancel_next = true;
  ExpectError(common::ErrorKind::kHardware, "cancelled", [&] {
    for (int i = 0; i < 6; ++i) camera->Capture();  // after any frames completed before it
  });
  ExpectError(common::ErrorKind::kHardware, "gone", [&] { camera->Capture(); });
}

TEST(LibcameraDriverTest, FailedFramesAreRequeuedAndSkipped) {
  auto shared = std::make_shared<FakeLibcameraSession::Shared>();
  auto camera = MakeCamera(shared);
  shared->fail_frames = 3;
  EXPECT_EQ(camera->Capture().width, 8);
  shared->fail_frames = 1000;
  // Up to four good frames completed before the sensor went bad; after those, give up.
  ExpectError(common::ErrorKind::kHardware, "FrameError", [&] {
    for (int i = 0; i < 5; ++i) camera->Capture();
  });
}

TEST(LibcameraDriverTest, BuffersKeepCirculatingAndStopRunsOnDestruction) {
  auto shared = std::make_shared<FakeLibcameraSession::Shared>();
  {
    auto camera = MakeCamera(shared);
    // 4 buffers; 40 frames only arrive if every completed buffer is queued again.
    for (int i = 0; i < 40; ++i) camera->Capture();
    EXPECT_EQ(shared->double_queues, 0);
  }
  EXPECT_EQ(shared->stop_calls, 1);
}

TEST(LibcameraRealTest, CameraManagerListsWithoutCrashing) {
  std::vector<CameraInfo> cameras;
  try {
    cameras = ListLibcameraCameras();
  } catch (const common::Error& error) {
    GTEST_SKIP() << "libcamera unavailable here: " << error.what();
  }
  if (cameras.empty()) GTEST_SKIP() << "no libcamera camera on this machine";
  auto camera = OpenLibcameraCamera(cameras.front().id.substr(10));
  camera->SetExposure({0.01, 1.0});
  const Frame frame = camera->Capture();
  EXPECT_GT(frame.width, 0);
  EXPECT_NEAR(frame.exposure_s, 0.01, 0.001);
}

}  // namespace
}  // namespace svbtdf::acquire
