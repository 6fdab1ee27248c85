#include "svbtdf/acquire/v4l2_camera.h"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <ctime>
#include <exception>
#include <filesystem>
#include <utility>

#include "svbtdf/common/error.h"

namespace svbtdf::acquire {
namespace {

constexpr double kExposureUnitS = 100e-6;  // V4L2_CID_EXPOSURE_ABSOLUTE counts 100 us

class SystemV4l2Device : public V4l2Device {
 public:
  std::vector<std::string> ListDevicePaths() override {
    std::vector<std::pair<int, std::string>> nodes;
    std::error_code error;
    for (const auto& entry : std::filesystem::directory_iterator("/dev", error)) {
      const std::string name = entry.path().filename().string();
      if (name.rfind("video", 0) != 0 || name.size() == 5) continue;
      const std::string digits = name.substr(5);
      if (!std::all_of(digits.begin(), digits.end(), ::isdigit)) continue;
      nodes.emplace_back(std::stoi(digits), entry.path().string());
    }
    std::sort(nodes.begin(), nodes.end());
    std::vector<std::string> paths;
    for (auto& node : nodes) paths.push_back(std::move(node.second));
    return paths;
  }
  int Open(const std::string& path) override {
    const int fd = ::open(path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
    return fd >= 0 ? fd : -errno;
  }
  void Close(int fd) override { ::close(fd); }
  int Ioctl(int fd, unsigned long request, void* arg) override {
    int result;
    do {
      result = ::ioctl(fd, request, arg);
    } while (result == -1 && errno == EINTR);
    return result == -1 ? errno : 0;
  }
  void* Mmap(int fd, size_t length, off_t offset, int* error) override {
    void* address = ::mmap(nullptr, length, PROT_READ | PROT_WRITE, MAP_SHARED, fd, offset);
    if (address == MAP_FAILED) {
      *error = errno;
      return nullptr;
    }
    return address;
  }
  void Munmap(void* address, size_t length) override { ::munmap(address, length); }
  int Poll(int fd, int timeout_ms) override {
    pollfd entry{fd, POLLIN, 0};
    const int result = ::poll(&entry, 1, timeout_ms);
    if (result < 0) return errno == EINTR ? 1 : -errno;  // DQBUF then reports EAGAIN and we wait on
    return result;  // POLLERR also counts as ready: VIDIOC_DQBUF then names the real error
  }
  int64_t MonotonicNowNs() override {
    timespec now{};
    clock_gettime(CLOCK_MONOTONIC, &now);
    return static_cast<int64_t>(now.tv_sec) * 1000000000 + now.tv_nsec;
  }
};

std::string HintFor(int error) {
  switch (error) {
    case ENODEV:
    case ENXIO: return "the camera was disconnected; reconnect it and re-run to resume";
    case EBUSY: return "another program holds the camera; close it (see `fuser DEVICE`)";
    case EIO: return "I/O error on the bus; check the cable and USB port, then retry";
    case EACCES:
    case EPERM: return "no permission; add your user to the `video` group";
    case ETIMEDOUT: return "no frame arrived; check the camera is streaming and the USB bus";
    case ENOMEM: return "the driver could not allocate buffers; try fewer or smaller buffers";
    default: return "see the kernel log (dmesg) for the driver's reason";
  }
}

// Stepwise sizes are reported by their maximum, the size we would pick.
struct EnumeratedFormat {
  uint32_t fourcc = 0;
  std::string description;
  std::vector<std::pair<int, int>> sizes;
};

std::vector<EnumeratedFormat> EnumerateFormats(V4l2Device& device, int fd) {
  std::vector<EnumeratedFormat> formats;
  for (uint32_t index = 0;; ++index) {
    v4l2_fmtdesc desc{};
    desc.index = index;
    desc.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (device.Ioctl(fd, VIDIOC_ENUM_FMT, &desc) != 0) break;  // EINVAL ends the list
    EnumeratedFormat format;
    format.fourcc = desc.pixelformat;
    format.description = reinterpret_cast<const char*>(desc.description);
    for (uint32_t size_index = 0;; ++size_index) {
      v4l2_frmsizeenum size{};
      size.index = size_index;
      size.pixel_format = desc.pixelformat;
      if (device.Ioctl(fd, VIDIOC_ENUM_FRAMESIZES, &size) != 0) break;
      if (size.type == V4L2_FRMSIZE_TYPE_DISCRETE) {
        format.sizes.emplace_back(size.discrete.width, size.discrete.height);
      } else {
        format.sizes.emplace_back(size.stepwise.max_width, size.stepwise.max_height);
        break;
      }
    }
    formats.push_back(std::move(format));
  }
  return formats;
}

bool IsCaptureDevice(const v4l2_capability& caps) {
  const uint32_t effective =
      (caps.capabilities & V4L2_CAP_DEVICE_CAPS) ? caps.device_caps : caps.capabilities;
  return (effective & V4L2_CAP_VIDEO_CAPTURE) != 0;
}

void DescribeControls(V4l2Device& device, int fd, CameraInfo* info) {
  v4l2_queryctrl query{};
  query.id = V4L2_CTRL_FLAG_NEXT_CTRL;
  while (device.Ioctl(fd, VIDIOC_QUERYCTRL, &query) == 0) {
    const bool usable = !(query.flags & V4L2_CTRL_FLAG_DISABLED) &&
                        query.type != V4L2_CTRL_TYPE_CTRL_CLASS;
    if (usable) {
      std::string line = reinterpret_cast<const char*>(query.name);
      std::replace(line.begin(), line.end(), ' ', '_');
      std::transform(line.begin(), line.end(), line.begin(), ::tolower);
      line += " [" + std::to_string(query.minimum) + ", " + std::to_string(query.maximum) + "]";
      if (query.id == V4L2_CID_EXPOSURE_ABSOLUTE) {
        line += " 100us";
        info->min_exposure_s = query.minimum * kExposureUnitS;
        info->max_exposure_s = query.maximum * kExposureUnitS;
      }
      info->controls.push_back(line);
    }
    query.id |= V4L2_CTRL_FLAG_NEXT_CTRL;
  }
}

CameraInfo DescribeOpenDevice(V4l2Device& device, int fd, const std::string& path,
                              const v4l2_capability& caps) {
  CameraInfo info;
  info.id = "v4l2:" + path;
  info.model = reinterpret_cast<const char*>(caps.card);
  for (const auto& format : EnumerateFormats(device, fd)) {
    PixelLayout layout;
    int rank = 0;
    const std::string tag = DescribeV4l2Format(format.fourcc, &layout, &rank)
                                ? FourccToString(format.fourcc)
                                : FourccToString(format.fourcc) + "(unsupported)";
    if (format.sizes.empty()) info.formats.push_back(tag);
    for (const auto& [w, h] : format.sizes) {
      info.formats.push_back(tag + " " + std::to_string(w) + "x" + std::to_string(h));
    }
  }
  DescribeControls(device, fd, &info);
  return info;
}

std::string Hex(uint32_t value) {
  char text[16];
  std::snprintf(text, sizeof text, "0x%08x", value);
  return text;
}

}  // namespace

std::shared_ptr<V4l2Device> MakeSystemV4l2Device() { return std::make_shared<SystemV4l2Device>(); }

std::string FourccToString(uint32_t fourcc) {
  std::string text;
  for (int i = 0; i < 4; ++i) {
    const char c = static_cast<char>((fourcc >> (8 * i)) & 0xFF);
    if (c != ' ' && c != '\0') text += c;
  }
  return text;
}

bool DescribeV4l2Format(uint32_t fourcc, PixelLayout* layout, int* rank) {
  struct Entry {
    uint32_t fourcc;
    SampleLayout sample;
    int bits;
    const char* bayer;
    const char* name;
  };
  // Raw Bayer with the most bits first (unpacked before MIPI-packed at equal depth: same data,
  // cheaper to read), then mono, then the processed formats whose tone curve we cannot undo.
  static const Entry kTable[] = {
      {V4L2_PIX_FMT_SRGGB16, SampleLayout::kRaw16, 16, "RGGB", "SRGGB16"},
      {V4L2_PIX_FMT_SBGGR16, SampleLayout::kRaw16, 16, "BGGR", "SBGGR16"},
      {V4L2_PIX_FMT_SGRBG16, SampleLayout::kRaw16, 16, "GRBG", "SGRBG16"},
      {V4L2_PIX_FMT_SGBRG16, SampleLayout::kRaw16, 16, "GBRG", "SGBRG16"},
      {V4L2_PIX_FMT_SRGGB14, SampleLayout::kRaw16, 14, "RGGB", "SRGGB14"},
      {V4L2_PIX_FMT_SBGGR14, SampleLayout::kRaw16, 14, "BGGR", "SBGGR14"},
      {V4L2_PIX_FMT_SGRBG14, SampleLayout::kRaw16, 14, "GRBG", "SGRBG14"},
      {V4L2_PIX_FMT_SGBRG14, SampleLayout::kRaw16, 14, "GBRG", "SGBRG14"},
      {V4L2_PIX_FMT_SRGGB12, SampleLayout::kRaw16, 12, "RGGB", "SRGGB12"},
      {V4L2_PIX_FMT_SBGGR12, SampleLayout::kRaw16, 12, "BGGR", "SBGGR12"},
      {V4L2_PIX_FMT_SGRBG12, SampleLayout::kRaw16, 12, "GRBG", "SGRBG12"},
      {V4L2_PIX_FMT_SGBRG12, SampleLayout::kRaw16, 12, "GBRG", "SGBRG12"},
      {V4L2_PIX_FMT_SRGGB12P, SampleLayout::kMipiPacked12, 12, "RGGB", "SRGGB12P"},
      {V4L2_PIX_FMT_SBGGR12P, SampleLayout::kMipiPacked12, 12, "BGGR", "SBGGR12P"},
      {V4L2_PIX_FMT_SGRBG12P, SampleLayout::kMipiPacked12, 12, "GRBG", "SGRBG12P"},
      {V4L2_PIX_FMT_SGBRG12P, SampleLayout::kMipiPacked12, 12, "GBRG", "SGBRG12P"},
      {V4L2_PIX_FMT_SRGGB10, SampleLayout::kRaw16, 10, "RGGB", "SRGGB10"},
      {V4L2_PIX_FMT_SBGGR10, SampleLayout::kRaw16, 10, "BGGR", "SBGGR10"},
      {V4L2_PIX_FMT_SGRBG10, SampleLayout::kRaw16, 10, "GRBG", "SGRBG10"},
      {V4L2_PIX_FMT_SGBRG10, SampleLayout::kRaw16, 10, "GBRG", "SGBRG10"},
      {V4L2_PIX_FMT_SRGGB10P, SampleLayout::kMipiPacked10, 10, "RGGB", "SRGGB10P"},
      {V4L2_PIX_FMT_SBGGR10P, SampleLayout::kMipiPacked10, 10, "BGGR", "SBGGR10P"},
      {V4L2_PIX_FMT_SGRBG10P, SampleLayout::kMipiPacked10, 10, "GRBG", "SGRBG10P"},
      {V4L2_PIX_FMT_SGBRG10P, SampleLayout::kMipiPacked10, 10, "GBRG", "SGBRG10P"},
      {V4L2_PIX_FMT_SRGGB8, SampleLayout::kRaw8, 8, "RGGB", "SRGGB8"},
      {V4L2_PIX_FMT_SBGGR8, SampleLayout::kRaw8, 8, "BGGR", "SBGGR8"},
      {V4L2_PIX_FMT_SGRBG8, SampleLayout::kRaw8, 8, "GRBG", "SGRBG8"},
      {V4L2_PIX_FMT_SGBRG8, SampleLayout::kRaw8, 8, "GBRG", "SGBRG8"},
      {V4L2_PIX_FMT_Y16, SampleLayout::kRaw16, 16, "", "Y16"},
      {V4L2_PIX_FMT_Y12, SampleLayout::kRaw16, 12, "", "Y12"},
      {V4L2_PIX_FMT_Y10, SampleLayout::kRaw16, 10, "", "Y10"},
      {V4L2_PIX_FMT_GREY, SampleLayout::kRaw8, 8, "", "GREY"},
      {V4L2_PIX_FMT_RGB24, SampleLayout::kRgb24, 8, "", "RGB24"},
      {V4L2_PIX_FMT_BGR24, SampleLayout::kBgr24, 8, "", "BGR24"},
      {V4L2_PIX_FMT_YUYV, SampleLayout::kYuyv, 8, "", "YUYV"},
      {V4L2_PIX_FMT_MJPEG, SampleLayout::kJpeg, 8, "", "MJPEG"},
      {V4L2_PIX_FMT_JPEG, SampleLayout::kJpeg, 8, "", "JPEG"},
  };
  for (size_t i = 0; i < std::size(kTable); ++i) {
    if (kTable[i].fourcc != fourcc) continue;
    *layout = PixelLayout{kTable[i].sample, kTable[i].bits, kTable[i].bayer, kTable[i].name};
    *rank = static_cast<int>(i);
    return true;
  }
  return false;
}

std::vector<CameraInfo> ListV4l2Cameras() {
  auto device = MakeSystemV4l2Device();
  return ListV4l2Cameras(*device);
}

std::vector<CameraInfo> ListV4l2Cameras(V4l2Device& device) {
  std::vector<CameraInfo> cameras;
  for (const std::string& path : device.ListDevicePaths()) {
    const int fd = device.Open(path);
    if (fd < 0) {
      CameraInfo unavailable;
      unavailable.id = "v4l2:" + path;
      unavailable.model = std::string("(cannot open: ") + std::strerror(-fd) + ")";
      cameras.push_back(std::move(unavailable));
      continue;
    }
    v4l2_capability caps{};
    if (device.Ioctl(fd, VIDIOC_QUERYCAP, &caps) == 0 && IsCaptureDevice(caps)) {
      cameras.push_back(DescribeOpenDevice(device, fd, path, caps));
    }
    device.Close(fd);
  }
  return cameras;
}

std::unique_ptr<Camera> OpenV4l2Camera(const std::string& device_path,
                                       const V4l2Options& options) {
  return std::make_unique<V4l2Camera>(MakeSystemV4l2Device(), device_path, options);
}

V4l2Camera::V4l2Camera(std::shared_ptr<V4l2Device> device, std::string path, V4l2Options options)
    : device_(std::move(device)), path_(std::move(path)), options_(std::move(options)) {
  if (options_.buffer_count < 2) {
    common::ThrowInvalidInput(path_, "buffer_count must be at least 2 for streaming");
  }
  fd_ = device_->Open(path_);
  if (fd_ < 0) {
    const int error = -fd_;
    fd_ = -1;
    Fail("open", error);
  }
  try {
    Negotiate();
    QueryControls();
    StartStreaming();
  } catch (...) {
    Release();
    throw;
  }
}

V4l2Camera::~V4l2Camera() { Release(); }

void V4l2Camera::Fail(const std::string& call, int error) const {
  throw common::Error(common::ErrorKind::kHardware, path_, call + " failed: " + std::strerror(error),
              HintFor(error));
}

void V4l2Camera::Negotiate() {
  v4l2_capability caps{};
  if (const int error = device_->Ioctl(fd_, VIDIOC_QUERYCAP, &caps)) Fail("VIDIOC_QUERYCAP", error);
  const uint32_t effective =
      (caps.capabilities & V4L2_CAP_DEVICE_CAPS) ? caps.device_caps : caps.capabilities;
  if (!(effective & V4L2_CAP_VIDEO_CAPTURE)) {
    throw common::Error(common::ErrorKind::kHardware, path_,
                "is not a single-planar video capture device (capabilities " + Hex(effective) + ")",
                "pick another /dev/video node; `svbtdf devices` lists the capture-capable ones");
  }
  if (!(effective & V4L2_CAP_STREAMING)) {
    throw common::Error(common::ErrorKind::kHardware, path_, "does not support memory-mapped streaming",
                "read()-only devices are not supported");
  }
  info_ = DescribeOpenDevice(*device_, fd_, path_, caps);

  std::vector<V4l2FormatChoice> choices;
  std::string offered;
  for (const auto& format : EnumerateFormats(*device_, fd_)) {
    offered += (offered.empty() ? "" : ", ") + FourccToString(format.fourcc);
    V4l2FormatChoice choice;
    choice.fourcc = format.fourcc;
    if (!DescribeV4l2Format(format.fourcc, &choice.layout, &choice.rank)) continue;
    if (!options_.fourcc.empty() && FourccToString(format.fourcc) != options_.fourcc) continue;
    for (const auto& [w, h] : format.sizes) {
      if (static_cast<int64_t>(w) * h > static_cast<int64_t>(choice.width) * choice.height) {
        choice.width = w;
        choice.height = h;
      }
    }
    if (options_.width > 0 && options_.height > 0) {
      choice.width = options_.width;
      choice.height = options_.height;
    }
    choices.push_back(choice);
  }
  if (choices.empty()) {
    throw common::Error(common::ErrorKind::kHardware, path_,
                options_.fourcc.empty() ? "offers no pixel format svbtdf can decode (" + offered + ")"
                                        : "does not offer format " + options_.fourcc + " (" + offered + ")",
                "svbtdf reads raw Bayer, GREY/Y10/Y12/Y16, RGB24/BGR24, YUYV and MJPEG");
  }
  const auto best = std::min_element(choices.begin(), choices.end(),
                                     [](const auto& a, const auto& b) { return a.rank < b.rank; });
  v4l2_format format{};
  format.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (best->width == 0) {  // no frame sizes enumerated: keep the current size
    if (const int error = device_->Ioctl(fd_, VIDIOC_G_FMT, &format)) Fail("VIDIOC_G_FMT", error);
  }
  format.fmt.pix.pixelformat = best->fourcc;
  if (best->width > 0) {
    format.fmt.pix.width = best->width;
    format.fmt.pix.height = best->height;
  }
  format.fmt.pix.field = V4L2_FIELD_NONE;
  if (const int error = device_->Ioctl(fd_, VIDIOC_S_FMT, &format)) Fail("VIDIOC_S_FMT", error);
  // The driver may adjust anything; trust only what it returned.
  format_.fourcc = format.fmt.pix.pixelformat;
  if (!DescribeV4l2Format(format_.fourcc, &format_.layout, &format_.rank)) {
    throw common::Error(common::ErrorKind::kHardware, path_,
                "VIDIOC_S_FMT switched to unsupported format " + FourccToString(format_.fourcc),
                "request another format with the camera options");
  }
  format_.width = static_cast<int>(format.fmt.pix.width);
  format_.height = static_cast<int>(format.fmt.pix.height);
  stride_ = std::max<size_t>(format.fmt.pix.bytesperline,
                             MinimumStride(format_.layout, format_.width));
}

V4l2Camera::ControlRange V4l2Camera::QueryControl(uint32_t id) {
  v4l2_queryctrl query{};
  query.id = id;
  ControlRange range;
  const int error = device_->Ioctl(fd_, VIDIOC_QUERYCTRL, &query);
  if (error == EINVAL) return range;  // the device has no such control
  if (error != 0) Fail("VIDIOC_QUERYCTRL", error);
  if (query.flags & V4L2_CTRL_FLAG_DISABLED) return range;
  range.present = true;
  range.id = id;
  range.minimum = query.minimum;
  range.maximum = query.maximum;
  range.step = std::max<int64_t>(1, query.step);
  range.default_value = query.default_value;
  return range;
}

void V4l2Camera::QueryControls() {
  exposure_ = QueryControl(V4L2_CID_EXPOSURE_ABSOLUTE);
  gain_ = QueryControl(V4L2_CID_ANALOGUE_GAIN);
  if (!gain_.present) gain_ = QueryControl(V4L2_CID_GAIN);
  has_exposure_auto_ = QueryControl(V4L2_CID_EXPOSURE_AUTO).present;
  has_autogain_ = QueryControl(V4L2_CID_AUTOGAIN).present;
  if (exposure_.present) {
    exposure_s_ = GetControl(exposure_.id, "V4L2_CID_EXPOSURE_ABSOLUTE") * kExposureUnitS;
  }
}

void V4l2Camera::SetControl(uint32_t id, int64_t value, const char* name) {
  v4l2_control control{};
  control.id = id;
  control.value = static_cast<int32_t>(value);
  if (const int error = device_->Ioctl(fd_, VIDIOC_S_CTRL, &control)) {
    if (error == ENODEV) broken_ = true;
    Fail(std::string("VIDIOC_S_CTRL(") + name + ")", error);
  }
}

int64_t V4l2Camera::GetControl(uint32_t id, const char* name) {
  v4l2_control control{};
  control.id = id;
  if (const int error = device_->Ioctl(fd_, VIDIOC_G_CTRL, &control)) {
    if (error == ENODEV) broken_ = true;
    Fail(std::string("VIDIOC_G_CTRL(") + name + ")", error);
  }
  return control.value;
}

void V4l2Camera::StartStreaming() {
  v4l2_requestbuffers request{};
  request.count = static_cast<uint32_t>(options_.buffer_count);
  request.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  request.memory = V4L2_MEMORY_MMAP;
  if (const int error = device_->Ioctl(fd_, VIDIOC_REQBUFS, &request)) Fail("VIDIOC_REQBUFS", error);
  if (request.count < 2) {
    throw common::Error(common::ErrorKind::kHardware, path_,
                "VIDIOC_REQBUFS granted only " + std::to_string(request.count) + " buffer(s)",
                "the driver is short of memory; close other camera programs");
  }
  for (uint32_t index = 0; index < request.count; ++index) {
    v4l2_buffer buffer{};
    buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buffer.memory = V4L2_MEMORY_MMAP;
    buffer.index = index;
    if (const int error = device_->Ioctl(fd_, VIDIOC_QUERYBUF, &buffer)) Fail("VIDIOC_QUERYBUF", error);
    int error = 0;
    void* start = device_->Mmap(fd_, buffer.length, buffer.m.offset, &error);
    if (start == nullptr) Fail("mmap", error);
    buffers_.push_back({start, buffer.length});
  }
  for (uint32_t index = 0; index < buffers_.size(); ++index) {
    v4l2_buffer buffer{};
    buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buffer.memory = V4L2_MEMORY_MMAP;
    buffer.index = index;
    if (const int error = device_->Ioctl(fd_, VIDIOC_QBUF, &buffer)) Fail("VIDIOC_QBUF", error);
  }
  int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (const int error = device_->Ioctl(fd_, VIDIOC_STREAMON, &type)) Fail("VIDIOC_STREAMON", error);
  streaming_ = true;
}

void V4l2Camera::Release() noexcept {
  if (fd_ < 0) return;
  if (streaming_) {
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    device_->Ioctl(fd_, VIDIOC_STREAMOFF, &type);  // fails harmlessly on an unplugged device
    streaming_ = false;
  }
  for (const Buffer& buffer : buffers_) device_->Munmap(buffer.start, buffer.length);
  if (!buffers_.empty()) {
    v4l2_requestbuffers request{};  // count 0 frees the driver's buffers
    request.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    request.memory = V4L2_MEMORY_MMAP;
    device_->Ioctl(fd_, VIDIOC_REQBUFS, &request);
  }
  buffers_.clear();
  device_->Close(fd_);
  fd_ = -1;
}

void V4l2Camera::SetExposure(const ExposureSettings& settings) {
  if (broken_) Fail("VIDIOC_S_CTRL", ENODEV);
  if (!std::isfinite(settings.exposure_s) || settings.exposure_s <= 0.0) {
    common::ThrowInvalidInput(path_, "exposure must be a positive number of seconds");
  }
  if (!exposure_.present) {
    throw common::Error(common::ErrorKind::kHardware, path_, "has no V4L2_CID_EXPOSURE_ABSOLUTE control",
                "this sensor's exposure is not in time units; use the libcamera backend");
  }
  const double lo = exposure_.minimum * kExposureUnitS, hi = exposure_.maximum * kExposureUnitS;
  const double half_unit = 0.5 * kExposureUnitS;
  if (settings.exposure_s < lo - half_unit || settings.exposure_s > hi + half_unit) {
    common::ThrowInvalidInput(path_, "exposure " + std::to_string(settings.exposure_s) +
                                 " s is outside the camera's range [" + std::to_string(lo) +
                                 ", " + std::to_string(hi) + "] s");
  }
  int64_t units = std::llround(settings.exposure_s / kExposureUnitS);
  units = exposure_.minimum +
          (units - exposure_.minimum + exposure_.step / 2) / exposure_.step * exposure_.step;
  units = std::clamp(units, exposure_.minimum, exposure_.maximum);

  int64_t gain_value = 0;
  if (gain_.present) {
    if (options_.gain_units_per_unity > 0.0) {
      gain_value = std::llround(settings.gain * options_.gain_units_per_unity);
      if (gain_value < gain_.minimum || gain_value > gain_.maximum) {
        common::ThrowInvalidInput(path_, "gain " + std::to_string(settings.gain) + " is outside [" +
                                     std::to_string(gain_.minimum / options_.gain_units_per_unity) +
                                     ", " + std::to_string(gain_.maximum / options_.gain_units_per_unity) + "]");
      }
    } else if (std::abs(settings.gain - 1.0) > 1e-9) {
      common::ThrowInvalidInput(path_, "V4L2 gain units are device specific; only gain 1.0 (base gain) is accepted",
                        "set the gain units per 1.0x in the camera options to use other gains");
    } else {
      gain_value = gain_.minimum;
    }
  } else if (std::abs(settings.gain - 1.0) > 1e-9) {
    common::ThrowInvalidInput(path_, "has no gain control; only gain 1.0 is possible");
  }

  if (units == applied_exposure_units_ && gain_value == applied_gain_value_) return;
  if (has_exposure_auto_) SetControl(V4L2_CID_EXPOSURE_AUTO, V4L2_EXPOSURE_MANUAL, "V4L2_CID_EXPOSURE_AUTO");
  if (has_autogain_) SetControl(V4L2_CID_AUTOGAIN, 0, "V4L2_CID_AUTOGAIN");
  SetControl(exposure_.id, units, "V4L2_CID_EXPOSURE_ABSOLUTE");
  if (gain_.present) SetControl(gain_.id, gain_value, "gain");
  // Read back: drivers may round to what the sensor can do.
  exposure_s_ = GetControl(exposure_.id, "V4L2_CID_EXPOSURE_ABSOLUTE") * kExposureUnitS;
  if (gain_.present && options_.gain_units_per_unity > 0.0) {
    gain_ratio_ = GetControl(gain_.id, "gain") / options_.gain_units_per_unity;
  } else {
    gain_ratio_ = 1.0;
  }
  applied_exposure_units_ = units;
  applied_gain_value_ = gain_value;
  change_time_ns_ = device_->MonotonicNowNs();
  frames_to_discard_after_change_ = options_.exposure_latency_frames;
  stale_frames_discarded_ = 0;
}

Frame V4l2Camera::DequeueFrame(int64_t* timestamp_ns, bool* monotonic) {
  const double timeout_s = options_.frame_timeout_s + 3.0 * exposure_s_;
  const int64_t deadline = device_->MonotonicNowNs() + static_cast<int64_t>(timeout_s * 1e9);
  int damaged_frames = 0;
  for (;;) {
    const int64_t remaining_ms = (deadline - device_->MonotonicNowNs()) / 1000000;
    const int ready = remaining_ms > 0 ? device_->Poll(fd_, static_cast<int>(remaining_ms)) : 0;
    if (ready < 0) {
      if (-ready == ENODEV) broken_ = true;
      Fail("poll", -ready);
    }
    if (ready == 0) {
      throw common::Error(common::ErrorKind::kHardware, path_,
                  "no frame within " + std::to_string(timeout_s) + " s (poll before VIDIOC_DQBUF)",
                  HintFor(ETIMEDOUT));
    }
    v4l2_buffer buffer{};
    buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buffer.memory = V4L2_MEMORY_MMAP;
    const int error = device_->Ioctl(fd_, VIDIOC_DQBUF, &buffer);
    if (error == EAGAIN) continue;
    if (error != 0) {
      if (error == ENODEV) broken_ = true;
      Fail("VIDIOC_DQBUF", error);
    }
    if (buffer.index >= buffers_.size()) {
      throw common::Error(common::ErrorKind::kHardware, path_,
                  "VIDIOC_DQBUF returned unknown buffer " + std::to_string(buffer.index));
    }
    Frame frame;
    std::exception_ptr decode_error;
    const bool damaged = (buffer.flags & V4L2_BUF_FLAG_ERROR) != 0;
    if (!damaged) {
      try {
        const size_t used = buffer.bytesused > 0 ? buffer.bytesused : buffers_[buffer.index].length;
        frame = DecodeImage(format_.layout, static_cast<const uint8_t*>(buffers_[buffer.index].start),
                            std::min(used, buffers_[buffer.index].length), format_.width,
                            format_.height, stride_, path_);
      } catch (...) {
        decode_error = std::current_exception();
      }
    }
    // The buffer goes back to the driver whatever happened to its contents.
    if (const int requeue_error = device_->Ioctl(fd_, VIDIOC_QBUF, &buffer)) {
      if (requeue_error == ENODEV) broken_ = true;
      Fail("VIDIOC_QBUF", requeue_error);
    }
    if (decode_error) std::rethrow_exception(decode_error);
    if (damaged) {
      if (++damaged_frames > static_cast<int>(buffers_.size()) + 2) {
        throw common::Error(common::ErrorKind::kHardware, path_, "every frame arrives flagged V4L2_BUF_FLAG_ERROR",
                    HintFor(EIO));
      }
      continue;
    }
    *timestamp_ns = static_cast<int64_t>(buffer.timestamp.tv_sec) * 1000000000 +
                    static_cast<int64_t>(buffer.timestamp.tv_usec) * 1000;
    *monotonic = (buffer.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC;
    return frame;
  }
}

Frame V4l2Camera::Capture() {
  if (broken_) Fail("VIDIOC_DQBUF", ENODEV);
  for (;;) {
    int64_t timestamp_ns = 0;
    bool monotonic = false;
    Frame frame = DequeueFrame(&timestamp_ns, &monotonic);
    if (change_time_ns_ >= 0) {
      // A frame stamped before the control write was certainly exposed with the old value.
      // If timestamps never pass the write (a driver with a mislabelled clock), stop trusting
      // them after as many frames as the count-only fallback would have dropped.
      const int count_fallback = static_cast<int>(buffers_.size()) + options_.exposure_latency_frames;
      const bool stamped_before = monotonic && timestamp_ns <= change_time_ns_ &&
                                  stale_frames_discarded_ < count_fallback;
      if (stamped_before || (!monotonic && stale_frames_discarded_ < static_cast<int>(buffers_.size()))) {
        ++stale_frames_discarded_;
        continue;
      }
      if (frames_to_discard_after_change_ > 0) {
        --frames_to_discard_after_change_;
        continue;
      }
      change_time_ns_ = -1;
    }
    frame.exposure_s = exposure_s_;
    frame.gain = gain_ratio_;
    return frame;
  }
}

}  // namespace svbtdf::acquire
