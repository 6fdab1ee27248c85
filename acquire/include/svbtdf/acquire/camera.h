#pragma once
// The camera interface of the capture rig. Real drivers (V4L2, libcamera, libgphoto2) and the
// simulated camera implement it; the capture loop only ever talks to this interface.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "svbtdf/session/rig.h"

namespace svbtdf::acquire {

// One captured frame in camera-native units, before any radiometric processing.
struct Frame {
  int width = 0;
  int height = 0;
  int channels = 0;           // 1 (mono or raw Bayer mosaic) or 3 (RGB)
  int bits_per_sample = 16;   // significant bits of the sensor data (8, 10, 12, 14 or 16)
  bool linear = true;         // false when the camera applied a tone curve (YUYV, MJPEG, JPEG)
  std::string bayer_pattern;  // "RGGB", "BGGR", "GRBG", "GBRG" for raw mosaics, empty otherwise
  double exposure_s = 0.0;    // the exposure actually used, as reported by the camera
  double gain = 1.0;          // the analogue gain actually used
  std::vector<uint16_t> pixels;  // row-major, interleaved channels, values in [0, 2^bits - 1]
};

struct ExposureSettings {
  double exposure_s = 0.01;
  double gain = 1.0;
};

// What a camera can do, for `svbtdf devices` and plan validation.
struct CameraInfo {
  std::string id;      // the --camera argument that selects it, e.g. "v4l2:/dev/video0"
  std::string model;   // human-readable name
  std::vector<std::string> formats;   // e.g. "SRGGB10 1920x1080", "YUYV 640x480"
  std::vector<std::string> controls;  // e.g. "exposure_time_absolute [1, 10000] 100us"
  double min_exposure_s = 0.0;
  double max_exposure_s = 0.0;
  // The frames Capture() delivers, when the backend knows before the first one (0 = unknown);
  // recorded in a new session's manifest (rig.camera).
  int frame_width = 0, frame_height = 0, frame_channels = 0, frame_bits = 0;
  // When the frames are a window (region of interest) of a larger sensor: the sensor's size and
  // the window's top-left pixel on it. Board views for Zhang calibration (Scene::kBoardView) are
  // then whole-sensor frames.
  session::SensorWindow window;
};

class Camera {
 public:
  virtual ~Camera() = default;
  virtual CameraInfo Info() const = 0;
  // Applies manual exposure and gain (auto-exposure off). Frames captured afterwards must have
  // been exposed with these settings: drivers discard frames until the change has taken effect.
  virtual void SetExposure(const ExposureSettings& settings) = 0;
  // Captures one frame. Throws svbtdf::Error(kHardware) on failure; the caller retries.
  virtual Frame Capture() = 0;
};

}  // namespace svbtdf::acquire
