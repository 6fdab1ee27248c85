#pragma once
// A scripted V4L2 driver for tests: it answers the ioctls V4l2Camera uses the way a kernel
// driver does (formats, controls, the buffer queue), models a sensor whose exposure changes
// take effect only after the queued buffers and a latency of whole frames, and fails on cue
// (open errors, ioctl errors, unplugging mid-stream, stalls). It records every ioctl so tests
// can check sequences, and tracks mappings and descriptors so tests can check for leaks.

#include <linux/videodev2.h>

#include <cerrno>
#include <cstring>
#include <deque>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "svbtdf/acquire/v4l2_camera.h"

namespace svbtdf::acquire::testing {

struct FakeFormat {
  uint32_t fourcc;
  std::vector<std::pair<int, int>> sizes;
};

struct FakeControl {
  int32_t minimum = 0, maximum = 100, step = 1, default_value = 0, value = 0;
  uint32_t type = V4L2_CTRL_TYPE_INTEGER;
  const char* name = "control";
};

struct FakeNode {
  std::string card = "Fake Camera";
  uint32_t device_caps = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;
  int open_error = 0;  // errno returned by open, 0 = opens
  std::vector<FakeFormat> formats;
  std::map<uint32_t, FakeControl> controls;
};

inline std::string IoctlName(unsigned long request) {
  switch (request) {
    case VIDIOC_QUERYCAP: return "QUERYCAP";
    case VIDIOC_ENUM_FMT: return "ENUM_FMT";
    case VIDIOC_ENUM_FRAMESIZES: return "ENUM_FRAMESIZES";
    case VIDIOC_G_FMT: return "G_FMT";
    case VIDIOC_S_FMT: return "S_FMT";
    case VIDIOC_QUERYCTRL: return "QUERYCTRL";
    case VIDIOC_G_CTRL: return "G_CTRL";
    case VIDIOC_S_CTRL: return "S_CTRL";
    case VIDIOC_REQBUFS: return "REQBUFS";
    case VIDIOC_QUERYBUF: return "QUERYBUF";
    case VIDIOC_QBUF: return "QBUF";
    case VIDIOC_DQBUF: return "DQBUF";
    case VIDIOC_STREAMON: return "STREAMON";
    case VIDIOC_STREAMOFF: return "STREAMOFF";
    default: return "?";
  }
}

class FakeV4l2Device : public V4l2Device {
 public:
  // --- configuration and scripts ---
  std::map<std::string, FakeNode> nodes;
  std::map<unsigned long, int> fail_ioctl;  // request -> errno, always
  int fail_mmap_at_index = -1;              // mmap of this buffer fails with ENOMEM
  int unplug_after_frames = -1;             // device vanishes after this many dequeues
  bool stall = false;                       // no frame ever arrives (poll times out)
  int exposure_latency_frames = 2;          // frames after a write still exposed the old way
  int32_t exposure_rounding = 1;            // the "driver" rounds exposure down to this multiple
  bool monotonic_timestamps = true;
  std::set<int> damaged_frames;             // frame numbers flagged V4L2_BUF_FLAG_ERROR
  std::vector<uint8_t> jpeg_payload;        // what MJPEG frames contain
  int64_t frame_interval_ns = 33'000'000;

  // --- observations ---
  std::vector<std::string> log;       // ioctl names in order ("S_CTRL:<id>=<value>" for S_CTRL)
  std::set<int> open_fds;
  std::set<const void*> mapped;
  std::vector<uint32_t> queued_indices;  // buffers the driver holds
  int frames_produced = 0, frames_dequeued = 0, double_queue_errors = 0;
  uint32_t active_fourcc = 0;
  int active_width = 0, active_height = 0;

  FakeV4l2Device() {
    FakeNode node;
    node.formats = {{V4L2_PIX_FMT_SRGGB12, {{8, 4}}}};
    node.controls[V4L2_CID_EXPOSURE_AUTO] = {0, 3, 1, 3, 3, V4L2_CTRL_TYPE_MENU, "Auto Exposure"};
    node.controls[V4L2_CID_EXPOSURE_ABSOLUTE] = {1, 5000, 1, 100, 100, V4L2_CTRL_TYPE_INTEGER,
                                                 "Exposure Time, Absolute"};
    node.controls[V4L2_CID_GAIN] = {16, 255, 1, 16, 16, V4L2_CTRL_TYPE_INTEGER, "Gain"};
    nodes["/dev/video0"] = node;
  }

  FakeNode& Node() { return nodes.begin()->second; }
  int32_t Control(uint32_t id) { return current_node_->controls.at(id).value; }

  std::vector<std::string> ListDevicePaths() override {
    std::vector<std::string> paths;
    for (const auto& [path, node] : nodes) paths.push_back(path);
    return paths;
  }

  int Open(const std::string& path) override {
    const auto node = nodes.find(path);
    if (node == nodes.end()) return -ENOENT;
    if (node->second.open_error) return -node->second.open_error;
    current_node_ = &node->second;
    const int fd = next_fd_++;
    open_fds.insert(fd);
    return fd;
  }

  void Close(int fd) override { open_fds.erase(fd); }

  int Ioctl(int fd, unsigned long request, void* arg) override {
    if (!open_fds.count(fd)) return EBADF;
    std::string entry = IoctlName(request);
    if (request == VIDIOC_S_CTRL) {
      const auto* control = static_cast<v4l2_control*>(arg);
      entry += ":" + std::to_string(control->id) + "=" + std::to_string(control->value);
    }
    if (request == VIDIOC_REQBUFS) {
      entry += ":" + std::to_string(static_cast<v4l2_requestbuffers*>(arg)->count);
    }
    log.push_back(entry);
    if (unplugged_) return ENODEV;
    if (const auto failure = fail_ioctl.find(request); failure != fail_ioctl.end()) return failure->second;
    switch (request) {
      case VIDIOC_QUERYCAP: return QueryCap(static_cast<v4l2_capability*>(arg));
      case VIDIOC_ENUM_FMT: return EnumFormat(static_cast<v4l2_fmtdesc*>(arg));
      case VIDIOC_ENUM_FRAMESIZES: return EnumSizes(static_cast<v4l2_frmsizeenum*>(arg));
      case VIDIOC_G_FMT: return GetFormat(static_cast<v4l2_format*>(arg));
      case VIDIOC_S_FMT: return SetFormat(static_cast<v4l2_format*>(arg));
      case VIDIOC_QUERYCTRL: return QueryControl(static_cast<v4l2_queryctrl*>(arg));
      case VIDIOC_G_CTRL: return GetControl(static_cast<v4l2_control*>(arg));
      case VIDIOC_S_CTRL: return SetControl(static_cast<v4l2_control*>(arg));
      case VIDIOC_REQBUFS: return RequestBuffers(static_cast<v4l2_requestbuffers*>(arg));
      case VIDIOC_QUERYBUF: return QueryBuffer(static_cast<v4l2_buffer*>(arg));
      case VIDIOC_QBUF: return Queue(static_cast<v4l2_buffer*>(arg));
      case VIDIOC_DQBUF: return Dequeue(static_cast<v4l2_buffer*>(arg));
      case VIDIOC_STREAMON: streaming_ = true; return 0;
      case VIDIOC_STREAMOFF:
        streaming_ = false;
        queued_indices.clear();
        done_.clear();
        return 0;
      default: return ENOTTY;
    }
  }

  void* Mmap(int fd, size_t length, off_t offset, int* error) override {
    const size_t index = static_cast<size_t>(offset) / kOffsetStride;
    if (static_cast<int>(index) == fail_mmap_at_index || index >= buffers_.size() ||
        length != buffers_[index].size()) {
      *error = ENOMEM;
      return nullptr;
    }
    mapped.insert(buffers_[index].data());
    return buffers_[index].data();
  }

  void Munmap(void* address, size_t) override { mapped.erase(address); }

  int Poll(int fd, int timeout_ms) override {
    if (unplugged_) return 1;  // POLLERR: DQBUF reports ENODEV
    if (stall || !streaming_ || (queued_indices.empty() && done_.empty())) {
      now_ns_ += static_cast<int64_t>(timeout_ms) * 1000000;
      return 0;
    }
    return 1;
  }

  int64_t MonotonicNowNs() override { return now_ns_; }

 private:
  static constexpr size_t kOffsetStride = 1 << 20;
  struct Done {
    uint32_t index;
    int64_t timestamp_ns;
    int frame_number;
  };

  int QueryCap(v4l2_capability* caps) {
    *caps = {};
    std::strncpy(reinterpret_cast<char*>(caps->card), current_node_->card.c_str(), sizeof caps->card - 1);
    caps->device_caps = current_node_->device_caps;
    caps->capabilities = current_node_->device_caps | V4L2_CAP_DEVICE_CAPS;
    return 0;
  }
  int EnumFormat(v4l2_fmtdesc* desc) {
    if (desc->index >= current_node_->formats.size()) return EINVAL;
    desc->pixelformat = current_node_->formats[desc->index].fourcc;
    return 0;
  }
  const FakeFormat* FindFormat(uint32_t fourcc) {
    for (const auto& format : current_node_->formats) {
      if (format.fourcc == fourcc) return &format;
    }
    return nullptr;
  }
  int EnumSizes(v4l2_frmsizeenum* size) {
    const FakeFormat* format = FindFormat(size->pixel_format);
    if (!format || size->index >= format->sizes.size()) return EINVAL;
    size->type = V4L2_FRMSIZE_TYPE_DISCRETE;
    size->discrete.width = format->sizes[size->index].first;
    size->discrete.height = format->sizes[size->index].second;
    return 0;
  }
  size_t BytesPerLine() const {
    switch (active_fourcc) {
      case V4L2_PIX_FMT_YUYV: return 2 * active_width;
      case V4L2_PIX_FMT_RGB24:
      case V4L2_PIX_FMT_BGR24: return 3 * active_width;
      case V4L2_PIX_FMT_GREY:
      case V4L2_PIX_FMT_SRGGB8: return active_width;
      case V4L2_PIX_FMT_MJPEG: return 0;
      default: return 2 * active_width;
    }
  }
  size_t ImageSize() const {
    return active_fourcc == V4L2_PIX_FMT_MJPEG ? 1 << 16 : BytesPerLine() * active_height;
  }
  void FillFormat(v4l2_format* format) const {
    format->fmt.pix.pixelformat = active_fourcc;
    format->fmt.pix.width = active_width;
    format->fmt.pix.height = active_height;
    format->fmt.pix.bytesperline = static_cast<uint32_t>(BytesPerLine());
    format->fmt.pix.sizeimage = static_cast<uint32_t>(ImageSize());
  }
  int GetFormat(v4l2_format* format) {
    if (active_fourcc == 0) {
      active_fourcc = current_node_->formats.at(0).fourcc;
      active_width = current_node_->formats.at(0).sizes.at(0).first;
      active_height = current_node_->formats.at(0).sizes.at(0).second;
    }
    FillFormat(format);
    return 0;
  }
  int SetFormat(v4l2_format* format) {
    if (!buffers_.empty()) return EBUSY;
    const FakeFormat* offered = FindFormat(format->fmt.pix.pixelformat);
    if (!offered) offered = &current_node_->formats.at(0);  // drivers substitute, never fail
    active_fourcc = offered->fourcc;
    active_width = offered->sizes.at(0).first;
    active_height = offered->sizes.at(0).second;
    for (const auto& [w, h] : offered->sizes) {
      if (static_cast<uint32_t>(w) == format->fmt.pix.width &&
          static_cast<uint32_t>(h) == format->fmt.pix.height) {
        active_width = w;
        active_height = h;
      }
    }
    FillFormat(format);
    return 0;
  }
  int QueryControl(v4l2_queryctrl* query) {
    std::map<uint32_t, FakeControl>::iterator control;
    if (query->id & V4L2_CTRL_FLAG_NEXT_CTRL) {
      control = current_node_->controls.upper_bound(query->id & ~V4L2_CTRL_FLAG_NEXT_CTRL);
    } else {
      control = current_node_->controls.find(query->id);
    }
    if (control == current_node_->controls.end()) return EINVAL;
    *query = {};
    query->id = control->first;
    query->type = control->second.type;
    std::strncpy(reinterpret_cast<char*>(query->name), control->second.name, sizeof query->name - 1);
    query->minimum = control->second.minimum;
    query->maximum = control->second.maximum;
    query->step = control->second.step;
    query->default_value = control->second.default_value;
    return 0;
  }
  int GetControl(v4l2_control* control) {
    const auto found = current_node_->controls.find(control->id);
    if (found == current_node_->controls.end()) return EINVAL;
    control->value = found->second.value;
    return 0;
  }
  int SetControl(v4l2_control* control) {
    const auto found = current_node_->controls.find(control->id);
    if (found == current_node_->controls.end()) return EINVAL;
    if (control->value < found->second.minimum || control->value > found->second.maximum) return ERANGE;
    int32_t value = control->value;
    if (control->id == V4L2_CID_EXPOSURE_ABSOLUTE) {
      value -= value % exposure_rounding;
      // Buffers already queued complete with the old exposure before the write lands, ...
      while (streaming_ && !queued_indices.empty()) Produce(now_ns_ - 1000);
      // ... and the sensor latches it only after `exposure_latency_frames` more frames.
      pending_.push_back({frames_produced + exposure_latency_frames, value});
    }
    found->second.value = value;
    return 0;
  }
  int RequestBuffers(v4l2_requestbuffers* request) {
    if (request->memory != V4L2_MEMORY_MMAP) return EINVAL;
    if (request->count == 0) {
      if (!mapped.empty()) return EBUSY;  // the kernel refuses to free mapped buffers
      buffers_.clear();
      return 0;
    }
    if (streaming_ || !mapped.empty()) return EBUSY;
    buffers_.assign(request->count, std::vector<uint8_t>(ImageSize()));
    return 0;
  }
  int QueryBuffer(v4l2_buffer* buffer) {
    if (buffer->index >= buffers_.size()) return EINVAL;
    buffer->length = static_cast<uint32_t>(buffers_[buffer->index].size());
    buffer->m.offset = static_cast<uint32_t>(buffer->index * kOffsetStride);
    return 0;
  }
  int Queue(v4l2_buffer* buffer) {
    if (buffer->index >= buffers_.size()) return EINVAL;
    for (uint32_t index : queued_indices) {
      if (index == buffer->index) {
        ++double_queue_errors;
        return EINVAL;
      }
    }
    for (const Done& done : done_) {
      if (done.index == buffer->index) {
        ++double_queue_errors;
        return EINVAL;
      }
    }
    queued_indices.push_back(buffer->index);
    return 0;
  }
  int Dequeue(v4l2_buffer* buffer) {
    if (!streaming_) return EINVAL;
    if (unplug_after_frames >= 0 && frames_dequeued >= unplug_after_frames) {
      unplugged_ = true;
      return ENODEV;
    }
    if (done_.empty()) {
      if (queued_indices.empty() || stall) return EAGAIN;
      now_ns_ += frame_interval_ns;
      Produce(now_ns_);
    }
    const Done done = done_.front();
    done_.pop_front();
    buffer->index = done.index;
    buffer->bytesused = static_cast<uint32_t>(
        active_fourcc == V4L2_PIX_FMT_MJPEG ? jpeg_payload.size() : ImageSize());
    buffer->timestamp.tv_sec = done.timestamp_ns / 1000000000;
    buffer->timestamp.tv_usec = (done.timestamp_ns % 1000000000) / 1000;
    buffer->flags = monotonic_timestamps ? V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC : V4L2_BUF_FLAG_TIMESTAMP_UNKNOWN;
    if (damaged_frames.count(done.frame_number)) buffer->flags |= V4L2_BUF_FLAG_ERROR;
    ++frames_dequeued;
    return 0;
  }
  // Fills the oldest queued buffer with a frame whose every sample is the exposure (in control
  // units) the sensor used for it, so tests can read which setting exposed a frame.
  void Produce(int64_t timestamp_ns) {
    while (!pending_.empty() && pending_.front().first <= frames_produced) {
      sensor_exposure_ = pending_.front().second;
      pending_.pop_front();
    }
    const uint32_t index = queued_indices.front();
    queued_indices.erase(queued_indices.begin());
    std::vector<uint8_t>& memory = buffers_[index];
    if (active_fourcc == V4L2_PIX_FMT_MJPEG) {
      std::copy(jpeg_payload.begin(), jpeg_payload.end(), memory.begin());
    } else if (BytesPerLine() == static_cast<size_t>(2 * active_width) && active_fourcc != V4L2_PIX_FMT_YUYV) {
      for (size_t i = 0; i + 1 < memory.size(); i += 2) {
        memory[i] = static_cast<uint8_t>(sensor_exposure_ & 0xFF);
        memory[i + 1] = static_cast<uint8_t>(sensor_exposure_ >> 8);
      }
    } else if (active_fourcc == V4L2_PIX_FMT_YUYV) {
      for (size_t i = 0; i + 1 < memory.size(); i += 2) {
        memory[i] = static_cast<uint8_t>(std::min(sensor_exposure_, 235));
        memory[i + 1] = 128;
      }
    } else {
      std::fill(memory.begin(), memory.end(), static_cast<uint8_t>(std::min(sensor_exposure_, 255)));
    }
    done_.push_back({index, timestamp_ns, frames_produced});
    ++frames_produced;
  }

  FakeNode* current_node_ = nullptr;
  int next_fd_ = 3;
  bool streaming_ = false, unplugged_ = false;
  int64_t now_ns_ = 1'000'000'000;
  int sensor_exposure_ = 100;
  std::deque<std::pair<int, int32_t>> pending_;  // (first frame number, exposure units)
  std::vector<std::vector<uint8_t>> buffers_;
  std::deque<Done> done_;
};

}  // namespace svbtdf::acquire::testing
