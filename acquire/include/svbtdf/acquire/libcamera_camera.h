#pragma once
// libcamera driver (the Debian 12 package's 0.0.3 API): one raw stream when the pipeline offers
// one, else a still-capture stream, with manual ExposureTime / AnalogueGain and AeEnable off.
// The libcamera objects sit behind LibcameraSession so that the request, timeout and
// exposure-settling logic of LibcameraCamera can be tested against a fake.

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "svbtdf/acquire/camera.h"
#include "svbtdf/acquire/frame_decode.h"

namespace svbtdf::acquire {

struct LibcameraStreamInfo {
  PixelLayout layout;
  int width = 0, height = 0;
  size_t stride = 0;
  int buffer_count = 0;
};

struct LibcameraRange {
  bool present = false;
  double minimum = 0.0, maximum = 0.0;  // seconds for exposure, a factor for gain
};

// One completed request, as seen by the requestCompleted slot.
struct LibcameraCompletion {
  int buffer_index = -1;              // the request's cookie
  bool cancelled = false;             // Request::RequestCancelled: stopped or unplugged
  bool frame_ok = false;              // FrameMetadata::FrameSuccess
  std::optional<double> exposure_s;   // metadata ExposureTime
  std::optional<double> gain;         // metadata AnalogueGain
};

// The thin seam over an acquired and configured libcamera camera with allocated, mapped
// buffers and one reusable Request per buffer.
class LibcameraSession {
 public:
  virtual ~LibcameraSession() = default;
  virtual CameraInfo Info() const = 0;
  virtual LibcameraStreamInfo Stream() const = 0;
  virtual LibcameraRange ExposureRange() const = 0;
  virtual LibcameraRange GainRange() const = 0;
  // Called for every completed request, possibly from libcamera's own thread.
  virtual void SetCompletionHandler(std::function<void(const LibcameraCompletion&)> handler) = 0;
  virtual int Start() = 0;  // 0 or a negative errno, as Camera::start()
  // Queues buffer `index`'s request with AeEnable = false and the given exposure and gain.
  virtual int Queue(int index, double exposure_s, double gain) = 0;  // 0 or negative errno
  // The mapped bytes of buffer `index`, valid until the buffer is queued again.
  virtual std::pair<const uint8_t*, size_t> BufferData(int index) const = 0;
  // Stops streaming; pending requests complete as cancelled before this returns.
  virtual void Stop() = 0;
};

// Opens the real libcamera camera `id` (a process-wide CameraManager is started on first use
// and shared by everything that lists or opens cameras).
std::unique_ptr<LibcameraSession> OpenLibcameraSession(const std::string& id);

struct LibcameraOptions {
  double initial_exposure_s = 0.01;
  double frame_timeout_s = 2.0;  // plus three exposure times
  // A frame counts as exposed with the requested setting when its metadata ExposureTime is
  // within max(relative * requested, absolute) of it (sensors quantise to line times).
  double exposure_tolerance_relative = 0.05;
  double exposure_tolerance_absolute_s = 100e-6;
  // Without ExposureTime in the metadata, drop this many frames after a change instead.
  int fallback_discard_frames = 4;
  // Give up when the metadata still disagrees after this many frames queued after the change.
  int max_settle_frames = 12;
};

std::vector<CameraInfo> ListLibcameraCameras();
std::unique_ptr<Camera> OpenLibcameraCamera(const std::string& id,
                                            const LibcameraOptions& options = {});

class LibcameraCamera : public Camera {
 public:
  // Starts streaming with every buffer queued. Throws Error(kHardware) on failure.
  LibcameraCamera(std::unique_ptr<LibcameraSession> session, std::string id,
                  LibcameraOptions options = {});
  ~LibcameraCamera() override;
  LibcameraCamera(const LibcameraCamera&) = delete;
  LibcameraCamera& operator=(const LibcameraCamera&) = delete;

  CameraInfo Info() const override;
  // Controls travel with each request, so a change applies to requests queued afterwards.
  // Capture() drops frames from requests queued before the change, then frames whose metadata
  // ExposureTime still disagrees with the request (the pipeline applies controls with a delay).
  void SetExposure(const ExposureSettings& settings) override;
  Frame Capture() override;

 private:
  [[noreturn]] void Fail(const std::string& call, const std::string& problem,
                         const std::string& hint) const;
  void Requeue(int index);
  LibcameraCompletion WaitForCompletion();

  std::unique_ptr<LibcameraSession> session_;
  std::string id_;
  LibcameraOptions options_;
  LibcameraStreamInfo stream_;
  double exposure_s_ = 0.0, gain_ = 1.0;
  uint64_t generation_ = 0;                     // bumped by every SetExposure that changes
  std::vector<uint64_t> buffer_generation_;     // generation each buffer was queued with
  int frames_since_change_ = 0;
  bool broken_ = false;
  bool started_ = false;

  std::mutex mutex_;
  std::condition_variable completed_;
  std::deque<LibcameraCompletion> completions_;
};

}  // namespace svbtdf::acquire
