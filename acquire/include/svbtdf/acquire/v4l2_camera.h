#pragma once
// Video4Linux2 camera driver: device discovery, format negotiation (raw Bayer first), memory-
// mapped streaming and manual exposure. Every system call goes through V4l2Device so that the
// negotiation, control and buffer logic can be tested against a scripted fake.

#include <sys/types.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "svbtdf/acquire/camera.h"
#include "svbtdf/acquire/frame_decode.h"

namespace svbtdf::acquire {

// The system-call boundary. Failures are returned as a positive errno value (0 = success) so
// that fakes need not touch the global errno.
class V4l2Device {
 public:
  virtual ~V4l2Device() = default;
  virtual std::vector<std::string> ListDevicePaths() = 0;  // the /dev/video* nodes, sorted
  // Returns a file descriptor >= 0, or -errno.
  virtual int Open(const std::string& path) = 0;
  virtual void Close(int fd) = 0;
  virtual int Ioctl(int fd, unsigned long request, void* arg) = 0;  // 0 or errno
  // Returns nullptr and sets *error on failure.
  virtual void* Mmap(int fd, size_t length, off_t offset, int* error) = 0;
  virtual void Munmap(void* address, size_t length) = 0;
  // Waits until a buffer can be dequeued: 1 ready, 0 timeout, -errno on failure.
  virtual int Poll(int fd, int timeout_ms) = 0;
  // CLOCK_MONOTONIC in nanoseconds, the clock V4L2 stamps buffers with.
  virtual int64_t MonotonicNowNs() = 0;
};

// The real device: open(2) with O_RDWR | O_NONBLOCK | O_CLOEXEC, ioctl(2) retried on EINTR.
std::shared_ptr<V4l2Device> MakeSystemV4l2Device();

struct V4l2Options {
  // Requested format; empty / 0 means "the best the device offers" (raw Bayer with the most
  // bits, then grey, RGB, YUYV, MJPEG; the largest frame size of that format).
  std::string fourcc;
  int width = 0, height = 0;
  int buffer_count = 4;
  // Frames the sensor needs after a control write before a frame is fully exposed with the new
  // value (register latching plus one frame already integrating). See SetExposure().
  int exposure_latency_frames = 2;
  // Raw V4L2 gain control units per 1.0x of gain. 0: unknown, and then only gain 1.0 (the
  // control's minimum, the sensor's base gain) is accepted; V4L2 defines no gain unit.
  double gain_units_per_unity = 0.0;
  // Poll timeout for one frame is this plus three times the exposure time.
  double frame_timeout_s = 2.0;
};

// One negotiable format, as found by VIDIOC_ENUM_FMT / VIDIOC_ENUM_FRAMESIZES.
struct V4l2FormatChoice {
  uint32_t fourcc = 0;
  int width = 0, height = 0;
  PixelLayout layout;
  int rank = 0;  // lower is preferred
};

// The layout and preference rank of a V4L2 pixel format, or false when we cannot decode it.
bool DescribeV4l2Format(uint32_t fourcc, PixelLayout* layout, int* rank);
std::string FourccToString(uint32_t fourcc);

// Describes every capture-capable device. Devices that cannot be opened (busy, no permission)
// are listed with the reason as their model so that `svbtdf devices` can tell the user.
std::vector<CameraInfo> ListV4l2Cameras();
std::vector<CameraInfo> ListV4l2Cameras(V4l2Device& device);

std::unique_ptr<Camera> OpenV4l2Camera(const std::string& device_path,
                                       const V4l2Options& options = {});

class V4l2Camera : public Camera {
 public:
  // Opens `path` through `device`, negotiates a format, maps buffers and starts streaming.
  // Throws Error(kHardware) on any failure, having released everything it acquired.
  V4l2Camera(std::shared_ptr<V4l2Device> device, std::string path, V4l2Options options = {});
  ~V4l2Camera() override;
  V4l2Camera(const V4l2Camera&) = delete;
  V4l2Camera& operator=(const V4l2Camera&) = delete;

  CameraInfo Info() const override { return info_; }
  // Exposure goes to V4L2_CID_EXPOSURE_ABSOLUTE (100 us units) with V4L2_CID_EXPOSURE_AUTO set
  // to manual. Frames are then discarded until the change has certainly taken effect: first
  // every frame stamped (CLOCK_MONOTONIC) no later than the control write, which covers the
  // buffers the driver had already filled, then `exposure_latency_frames` more, which covers
  // sensors that latch exposure registers only at a frame boundary. Devices whose timestamps
  // are not monotonic instead discard buffer_count + exposure_latency_frames frames.
  void SetExposure(const ExposureSettings& settings) override;
  Frame Capture() override;

  const V4l2FormatChoice& format() const { return format_; }

 private:
  struct Buffer {
    void* start = nullptr;
    size_t length = 0;
  };
  struct ControlRange {
    bool present = false;
    uint32_t id = 0;
    int64_t minimum = 0, maximum = 0, step = 1, default_value = 0;
  };

  [[noreturn]] void Fail(const std::string& call, int error) const;
  void Negotiate();
  void QueryControls();
  void StartStreaming();
  void Release() noexcept;
  ControlRange QueryControl(uint32_t id);
  void SetControl(uint32_t id, int64_t value, const char* name);
  int64_t GetControl(uint32_t id, const char* name);
  // Waits for, dequeues and decodes one frame, and requeues its buffer in every case.
  Frame DequeueFrame(int64_t* timestamp_ns, bool* monotonic);

  std::shared_ptr<V4l2Device> device_;
  std::string path_;
  V4l2Options options_;
  int fd_ = -1;
  bool streaming_ = false;
  bool broken_ = false;  // ENODEV seen: every later call fails fast
  std::vector<Buffer> buffers_;
  V4l2FormatChoice format_;
  size_t stride_ = 0;
  CameraInfo info_;
  ControlRange exposure_, gain_;
  bool has_exposure_auto_ = false, has_autogain_ = false;
  double exposure_s_ = 0.0, gain_ratio_ = 1.0;  // as read back from the device
  // Frame discard state after a control change.
  int64_t change_time_ns_ = -1;
  int frames_to_discard_after_change_ = 0;
  int stale_frames_discarded_ = 0;
  int64_t applied_exposure_units_ = -1, applied_gain_value_ = -1;  // skip no-op changes
};

}  // namespace svbtdf::acquire
