#include "svbtdf/acquire/libcamera_camera.h"

#include <sys/mman.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <libcamera/camera.h>
#include <libcamera/camera_manager.h>
#include <libcamera/control_ids.h>
#include <libcamera/formats.h>
#include <libcamera/framebuffer_allocator.h>
#include <libcamera/property_ids.h>
#include <libcamera/request.h>
#include <libcamera/stream.h>
#include <map>

#include "svbtdf/common/error.h"

namespace svbtdf::acquire {
namespace {

namespace lc = libcamera;

// libcamera's RGB888 / BGR888 follow DRM naming: RGB888 is B, G, R in memory.
bool DescribePixelFormat(const lc::PixelFormat& format, PixelLayout* layout, int* rank) {
  struct Entry {
    lc::PixelFormat format;
    SampleLayout sample;
    int bits;
    const char* bayer;
  };
  static const Entry kTable[] = {
      {lc::formats::SRGGB16, SampleLayout::kRaw16, 16, "RGGB"},
      {lc::formats::SBGGR16, SampleLayout::kRaw16, 16, "BGGR"},
      {lc::formats::SGRBG16, SampleLayout::kRaw16, 16, "GRBG"},
      {lc::formats::SGBRG16, SampleLayout::kRaw16, 16, "GBRG"},
      {lc::formats::SRGGB12, SampleLayout::kRaw16, 12, "RGGB"},
      {lc::formats::SBGGR12, SampleLayout::kRaw16, 12, "BGGR"},
      {lc::formats::SGRBG12, SampleLayout::kRaw16, 12, "GRBG"},
      {lc::formats::SGBRG12, SampleLayout::kRaw16, 12, "GBRG"},
      {lc::formats::SRGGB12_CSI2P, SampleLayout::kMipiPacked12, 12, "RGGB"},
      {lc::formats::SBGGR12_CSI2P, SampleLayout::kMipiPacked12, 12, "BGGR"},
      {lc::formats::SGRBG12_CSI2P, SampleLayout::kMipiPacked12, 12, "GRBG"},
      {lc::formats::SGBRG12_CSI2P, SampleLayout::kMipiPacked12, 12, "GBRG"},
      {lc::formats::SRGGB10, SampleLayout::kRaw16, 10, "RGGB"},
      {lc::formats::SBGGR10, SampleLayout::kRaw16, 10, "BGGR"},
      {lc::formats::SGRBG10, SampleLayout::kRaw16, 10, "GRBG"},
      {lc::formats::SGBRG10, SampleLayout::kRaw16, 10, "GBRG"},
      {lc::formats::SRGGB10_CSI2P, SampleLayout::kMipiPacked10, 10, "RGGB"},
      {lc::formats::SBGGR10_CSI2P, SampleLayout::kMipiPacked10, 10, "BGGR"},
      {lc::formats::SGRBG10_CSI2P, SampleLayout::kMipiPacked10, 10, "GRBG"},
      {lc::formats::SGBRG10_CSI2P, SampleLayout::kMipiPacked10, 10, "GBRG"},
      {lc::formats::SRGGB8, SampleLayout::kRaw8, 8, "RGGB"},
      {lc::formats::SBGGR8, SampleLayout::kRaw8, 8, "BGGR"},
      {lc::formats::SGRBG8, SampleLayout::kRaw8, 8, "GRBG"},
      {lc::formats::SGBRG8, SampleLayout::kRaw8, 8, "GBRG"},
      {lc::formats::R12, SampleLayout::kRaw16, 12, ""},
      {lc::formats::R10, SampleLayout::kRaw16, 10, ""},
      {lc::formats::R10_CSI2P, SampleLayout::kMipiPacked10, 10, ""},
      {lc::formats::R8, SampleLayout::kRaw8, 8, ""},
      {lc::formats::BGR888, SampleLayout::kRgb24, 8, ""},
      {lc::formats::RGB888, SampleLayout::kBgr24, 8, ""},
      {lc::formats::YUYV, SampleLayout::kYuyv, 8, ""},
      {lc::formats::MJPEG, SampleLayout::kJpeg, 8, ""},
  };
  for (size_t i = 0; i < std::size(kTable); ++i) {
    if (kTable[i].format != format) continue;
    *layout = PixelLayout{kTable[i].sample, kTable[i].bits, kTable[i].bayer, format.toString()};
    *rank = static_cast<int>(i);
    return true;
  }
  return false;
}

// libcamera allows one CameraManager per process; everything shares this one.
std::shared_ptr<lc::CameraManager> SharedCameraManager() {
  static std::mutex mutex;
  static std::weak_ptr<lc::CameraManager> shared;
  std::lock_guard lock(mutex);
  if (auto manager = shared.lock()) return manager;
  setenv("LIBCAMERA_LOG_LEVELS", "*:ERROR", /*overwrite=*/0);  // keep `svbtdf` output readable
  auto manager = std::make_shared<lc::CameraManager>();
  if (const int error = manager->start()) {
    throw common::Error(common::ErrorKind::kHardware, "libcamera",
                std::string("CameraManager::start failed: ") + std::strerror(-error),
                "check that the libcamera IPA modules are installed");
  }
  shared = manager;
  return manager;
}

LibcameraRange RangeOf(const lc::Camera& camera, const lc::ControlId& id, double scale) {
  LibcameraRange range;
  const auto& controls = camera.controls();
  const auto found = controls.find(&id);
  if (found == controls.end()) return range;
  const lc::ControlInfo& info = found->second;
  // Some pipelines advertise a control without limits; get<T>() on an empty value is invalid.
  if (info.min().type() != id.type() || info.max().type() != id.type()) return range;
  range.present = true;
  if (id.type() == lc::ControlTypeFloat) {
    range.minimum = info.min().get<float>() * scale;
    range.maximum = info.max().get<float>() * scale;
  } else {
    range.minimum = info.min().get<int32_t>() * scale;
    range.maximum = info.max().get<int32_t>() * scale;
  }
  return range;
}

CameraInfo DescribeCamera(lc::Camera& camera) {
  CameraInfo info;
  info.id = "libcamera:" + camera.id();
  info.model = camera.properties().get(lc::properties::Model).value_or(camera.id());
  for (const lc::StreamRole role : {lc::StreamRole::Raw, lc::StreamRole::StillCapture}) {
    const auto config = camera.generateConfiguration({role});
    if (!config || config->empty()) continue;
    const lc::StreamFormats& formats = config->at(0).formats();
    for (const lc::PixelFormat& format : formats.pixelformats()) {
      PixelLayout layout;
      int rank = 0;
      const std::string tag =
          format.toString() + (DescribePixelFormat(format, &layout, &rank) ? "" : "(unsupported)");
      const auto sizes = formats.sizes(format);
      info.formats.push_back(tag + (sizes.empty() ? "" : " " + sizes.back().toString()));
    }
  }
  std::sort(info.formats.begin(), info.formats.end());
  info.formats.erase(std::unique(info.formats.begin(), info.formats.end()), info.formats.end());
  for (const auto& [id, control] : camera.controls()) {
    info.controls.push_back(id->name() + " " + control.toString());
  }
  const LibcameraRange exposure = RangeOf(camera, lc::controls::ExposureTime, 1e-6);
  info.min_exposure_s = exposure.minimum;
  info.max_exposure_s = exposure.maximum;
  return info;
}

class RealLibcameraSession : public LibcameraSession {
 public:
  explicit RealLibcameraSession(const std::string& id) : id_(id) {
    manager_ = SharedCameraManager();
    camera_ = manager_->get(id);
    if (!camera_) {
      throw common::Error(common::ErrorKind::kHardware, "libcamera:" + id, "no such camera",
                  "`svbtdf devices` lists the connected cameras");
    }
    if (const int error = camera_->acquire()) {
      camera_.reset();
      Fail("Camera::acquire", error, "another program (libcamera-apps, a pipewire session) holds it");
    }
    try {
      Configure();
      AllocateAndMap();
    } catch (...) {
      Release();
      throw;
    }
    camera_->requestCompleted.connect(this, &RealLibcameraSession::OnRequestCompleted);
  }

  ~RealLibcameraSession() override { Release(); }

  CameraInfo Info() const override { return DescribeCamera(*camera_); }
  LibcameraStreamInfo Stream() const override { return stream_info_; }
  LibcameraRange ExposureRange() const override {
    return RangeOf(*camera_, lc::controls::ExposureTime, 1e-6);
  }
  LibcameraRange GainRange() const override {
    return RangeOf(*camera_, lc::controls::AnalogueGain, 1.0);
  }
  void SetCompletionHandler(std::function<void(const LibcameraCompletion&)> handler) override {
    handler_ = std::move(handler);
  }
  int Start() override {
    const int error = camera_->start();
    started_ = error == 0;
    return error;
  }
  int Queue(int index, double exposure_s, double gain) override {
    lc::Request& request = *requests_.at(index);
    request.reuse(lc::Request::ReuseBuffers);
    const auto& available = camera_->controls();
    if (available.find(&lc::controls::AeEnable) != available.end()) {
      request.controls().set(lc::controls::AeEnable, false);
    }
    request.controls().set(lc::controls::ExposureTime,
                           static_cast<int32_t>(std::lround(exposure_s * 1e6)));
    if (available.find(&lc::controls::AnalogueGain) != available.end()) {
      request.controls().set(lc::controls::AnalogueGain, static_cast<float>(gain));
    }
    return camera_->queueRequest(&request);
  }
  std::pair<const uint8_t*, size_t> BufferData(int index) const override {
    const Mapping& mapping = mappings_.at(index);
    return {static_cast<const uint8_t*>(mapping.address) + mapping.offset, mapping.length};
  }
  void Stop() override {
    if (started_) camera_->stop();
    started_ = false;
  }

 private:
  struct Mapping {
    void* address = nullptr;
    size_t mapped_length = 0, offset = 0, length = 0;
  };

  [[noreturn]] void Fail(const std::string& call, int error, const std::string& hint) const {
    throw common::Error(common::ErrorKind::kHardware, "libcamera:" + id_,
                call + " failed: " + std::strerror(std::abs(error)), hint);
  }

  // A raw stream when the pipeline offers one (linear sensor data), else still capture, in the
  // best format DescribePixelFormat ranks.
  void Configure() {
    for (const lc::StreamRole role : {lc::StreamRole::Raw, lc::StreamRole::StillCapture}) {
      config_ = camera_->generateConfiguration({role});
      if (!config_ || config_->empty()) continue;
      lc::StreamConfiguration& stream = config_->at(0);
      int best_rank = 1 << 30;
      for (const lc::PixelFormat& format : stream.formats().pixelformats()) {
        PixelLayout layout;
        int rank = 0;
        if (DescribePixelFormat(format, &layout, &rank) && rank < best_rank) {
          best_rank = rank;
          stream.pixelFormat = format;
        }
      }
      if (config_->validate() == lc::CameraConfiguration::Invalid) continue;
      int rank = 0;
      if (!DescribePixelFormat(stream.pixelFormat, &stream_info_.layout, &rank)) continue;
      if (const int error = camera_->configure(config_.get())) {
        Fail("Camera::configure", error, "the pipeline rejected its own configuration");
      }
      stream_ = stream.stream();
      stream_info_.width = static_cast<int>(stream.size.width);
      stream_info_.height = static_cast<int>(stream.size.height);
      stream_info_.stride = stream.stride;
      return;
    }
    throw common::Error(common::ErrorKind::kHardware, "libcamera:" + id_,
                "offers neither a raw nor a still stream in a format svbtdf can decode",
                "`svbtdf devices` lists its formats");
  }

  void AllocateAndMap() {
    allocator_ = std::make_unique<lc::FrameBufferAllocator>(camera_);
    if (const int error = allocator_->allocate(stream_); error < 0) {
      Fail("FrameBufferAllocator::allocate", error, "out of buffer memory (CMA)");
    }
    const auto& buffers = allocator_->buffers(stream_);
    for (size_t index = 0; index < buffers.size(); ++index) {
      const lc::FrameBuffer::Plane& plane = buffers[index]->planes().front();
      Mapping mapping;
      mapping.offset = plane.offset;
      mapping.length = plane.length;
      mapping.mapped_length = plane.offset + plane.length;
      mapping.address =
          mmap(nullptr, mapping.mapped_length, PROT_READ, MAP_SHARED, plane.fd.get(), 0);
      if (mapping.address == MAP_FAILED) Fail("mmap", errno, "cannot map the frame buffer");
      mappings_.push_back(mapping);
      std::unique_ptr<lc::Request> request = camera_->createRequest(index);
      if (!request) Fail("Camera::createRequest", ENOMEM, "the camera refused a request");
      if (const int error = request->addBuffer(stream_, buffers[index].get())) {
        Fail("Request::addBuffer", error, "the pipeline refused its own buffer");
      }
      requests_.push_back(std::move(request));
    }
    stream_info_.buffer_count = static_cast<int>(requests_.size());
  }

  void OnRequestCompleted(lc::Request* request) {
    LibcameraCompletion completion;
    completion.buffer_index = static_cast<int>(request->cookie());
    completion.cancelled = request->status() == lc::Request::RequestCancelled;
    if (const lc::FrameBuffer* buffer = request->findBuffer(stream_)) {
      completion.frame_ok = buffer->metadata().status == lc::FrameMetadata::FrameSuccess;
    }
    if (const auto exposure = request->metadata().get(lc::controls::ExposureTime)) {
      completion.exposure_s = *exposure * 1e-6;
    }
    if (const auto gain = request->metadata().get(lc::controls::AnalogueGain)) {
      completion.gain = *gain;
    }
    if (handler_) handler_(completion);
  }

  void Release() noexcept {
    if (!camera_) return;
    Stop();
    camera_->requestCompleted.disconnect(this);
    requests_.clear();
    for (const Mapping& mapping : mappings_) munmap(mapping.address, mapping.mapped_length);
    mappings_.clear();
    if (allocator_ && stream_) allocator_->free(stream_);
    allocator_.reset();
    camera_->release();
    camera_.reset();
  }

  std::string id_;
  std::shared_ptr<lc::CameraManager> manager_;  // declared first: outlives the camera
  std::shared_ptr<lc::Camera> camera_;
  std::unique_ptr<lc::CameraConfiguration> config_;
  lc::Stream* stream_ = nullptr;
  std::unique_ptr<lc::FrameBufferAllocator> allocator_;
  std::vector<std::unique_ptr<lc::Request>> requests_;
  std::vector<Mapping> mappings_;
  LibcameraStreamInfo stream_info_;
  std::function<void(const LibcameraCompletion&)> handler_;
  bool started_ = false;
};

}  // namespace

std::unique_ptr<LibcameraSession> OpenLibcameraSession(const std::string& id) {
  return std::make_unique<RealLibcameraSession>(id);
}

std::vector<CameraInfo> ListLibcameraCameras() {
  const auto manager = SharedCameraManager();
  std::vector<CameraInfo> cameras;
  for (const auto& camera : manager->cameras()) cameras.push_back(DescribeCamera(*camera));
  return cameras;
}

std::unique_ptr<Camera> OpenLibcameraCamera(const std::string& id,
                                            const LibcameraOptions& options) {
  return std::make_unique<LibcameraCamera>(OpenLibcameraSession(id), id, options);
}

LibcameraCamera::LibcameraCamera(std::unique_ptr<LibcameraSession> session, std::string id,
                                 LibcameraOptions options)
    : session_(std::move(session)), id_(std::move(id)), options_(std::move(options)) {
  stream_ = session_->Stream();
  const LibcameraRange exposure = session_->ExposureRange();
  exposure_s_ = exposure.present ? std::clamp(options_.initial_exposure_s, exposure.minimum,
                                              exposure.maximum)
                                 : options_.initial_exposure_s;
  buffer_generation_.assign(stream_.buffer_count, 0);
  session_->SetCompletionHandler([this](const LibcameraCompletion& completion) {
    {
      std::lock_guard lock(mutex_);
      completions_.push_back(completion);
    }
    completed_.notify_one();
  });
  if (const int error = session_->Start()) {
    Fail("Camera::start", std::strerror(std::abs(error)), "is another program using it?");
  }
  started_ = true;
  for (int index = 0; index < stream_.buffer_count; ++index) Requeue(index);
}

LibcameraCamera::~LibcameraCamera() {
  if (started_) session_->Stop();  // cancels pending requests before the handler's target dies
  session_->SetCompletionHandler(nullptr);
}

CameraInfo LibcameraCamera::Info() const { return session_->Info(); }

void LibcameraCamera::Fail(const std::string& call, const std::string& problem,
                           const std::string& hint) const {
  throw common::Error(common::ErrorKind::kHardware, "libcamera:" + id_, call + ": " + problem, hint);
}

void LibcameraCamera::Requeue(int index) {
  buffer_generation_.at(index) = generation_;
  if (const int error = session_->Queue(index, exposure_s_, gain_)) {
    if (std::abs(error) == ENODEV) broken_ = true;
    Fail("Camera::queueRequest", std::strerror(std::abs(error)),
         std::abs(error) == ENODEV ? "the camera was disconnected; reconnect it and re-run"
                                   : "the camera stopped streaming");
  }
}

void LibcameraCamera::SetExposure(const ExposureSettings& settings) {
  if (!std::isfinite(settings.exposure_s) || settings.exposure_s <= 0.0 ||
      !std::isfinite(settings.gain) || settings.gain <= 0.0) {
    common::ThrowInvalidInput("libcamera:" + id_, "exposure and gain must be positive numbers");
  }
  const LibcameraRange exposure = session_->ExposureRange();
  if (exposure.present &&
      (settings.exposure_s < exposure.minimum || settings.exposure_s > exposure.maximum)) {
    common::ThrowInvalidInput("libcamera:" + id_,
                      "exposure " + std::to_string(settings.exposure_s) + " s is outside [" +
                          std::to_string(exposure.minimum) + ", " +
                          std::to_string(exposure.maximum) + "] s");
  }
  const LibcameraRange gain = session_->GainRange();
  if (gain.present && (settings.gain < gain.minimum || settings.gain > gain.maximum)) {
    common::ThrowInvalidInput("libcamera:" + id_, "analogue gain " + std::to_string(settings.gain) +
                                              " is outside [" + std::to_string(gain.minimum) +
                                              ", " + std::to_string(gain.maximum) + "]");
  }
  if (!gain.present && std::abs(settings.gain - 1.0) > 1e-9) {
    common::ThrowInvalidInput("libcamera:" + id_, "has no AnalogueGain control; only gain 1.0 is possible");
  }
  if (settings.exposure_s == exposure_s_ && settings.gain == gain_) return;
  exposure_s_ = settings.exposure_s;
  gain_ = settings.gain;
  ++generation_;
  frames_since_change_ = 0;
}

LibcameraCompletion LibcameraCamera::WaitForCompletion() {
  const double timeout_s = options_.frame_timeout_s + 3.0 * exposure_s_;
  std::unique_lock lock(mutex_);
  const bool arrived = completed_.wait_for(lock, std::chrono::duration<double>(timeout_s),
                                           [this] { return !completions_.empty(); });
  if (!arrived) {
    Fail("requestCompleted", "no request completed within " + std::to_string(timeout_s) + " s",
         "check the camera is streaming and its cable is seated");
  }
  LibcameraCompletion completion = completions_.front();
  completions_.pop_front();
  return completion;
}

Frame LibcameraCamera::Capture() {
  if (broken_) Fail("Capture", "the camera is gone", "reconnect it and re-run to resume");
  int damaged = 0;
  for (;;) {
    const LibcameraCompletion completion = WaitForCompletion();
    const int index = completion.buffer_index;
    if (completion.cancelled) {
      broken_ = true;  // requests are only cancelled by stop() or a disconnect
      Fail("requestCompleted", "request cancelled", "the camera was stopped or disconnected");
    }
    if (index < 0 || index >= stream_.buffer_count) {
      Fail("requestCompleted", "unknown request cookie " + std::to_string(index), "");
    }
    const bool stale = buffer_generation_[index] != generation_;
    if (!completion.frame_ok) {
      Requeue(index);
      if (++damaged > stream_.buffer_count + 2) {
        Fail("requestCompleted", "every frame arrives with FrameError", "check the sensor cable");
      }
      continue;
    }
    if (stale) {  // queued with the previous settings
      Requeue(index);
      continue;
    }
    ++frames_since_change_;
    bool settled;
    if (completion.exposure_s) {
      const double tolerance = std::max(options_.exposure_tolerance_relative * exposure_s_,
                                        options_.exposure_tolerance_absolute_s);
      settled = std::abs(*completion.exposure_s - exposure_s_) <= tolerance;
      if (!settled && frames_since_change_ >= options_.max_settle_frames) {
        Requeue(index);
        Fail("ExposureTime", "the camera applies " + std::to_string(*completion.exposure_s) +
                                 " s instead of the requested " + std::to_string(exposure_s_) + " s",
             "the frame duration limits may cap the exposure; choose a shorter one");
      }
    } else {
      settled = frames_since_change_ > options_.fallback_discard_frames;
    }
    if (!settled) {
      Requeue(index);
      continue;
    }
    Frame frame;
    try {
      const auto [data, bytes] = session_->BufferData(index);
      frame = DecodeImage(stream_.layout, data, bytes, stream_.width, stream_.height,
                          stream_.stride, "libcamera:" + id_);
    } catch (...) {
      Requeue(index);
      throw;
    }
    Requeue(index);
    frame.exposure_s = completion.exposure_s.value_or(exposure_s_);
    frame.gain = completion.gain.value_or(gain_);
    return frame;
  }
}

}  // namespace svbtdf::acquire
