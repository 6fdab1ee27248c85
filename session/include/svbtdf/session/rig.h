#pragma once
// The rig description of a session manifest (session.json's `rig`, docs/session-format.md),
// typed: the camera with its sensor window, the monitor, the dots, the boards and the sample.
// Everything that writes or reads a rig goes through RigDescription, so each key is spelt once.
//
// Every field is optional in the file (0, NaN or empty when absent): readers say which ones they
// need (calibration needs the camera's size and bit depth, the board, the sample's size ...).
// A field of the wrong type is an error naming the file and the key.

#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

namespace svbtdf::session {

// Where the session's images lie on the camera's sensor (rig.camera.sensor). A lab crops its
// dot images to the region around the sample and calibrates the lens on the whole sensor: the
// Zhang board views are then whole-sensor images. sensor_width = 0: the images are the whole sensor.
struct SensorWindow {
  int sensor_width = 0;
  int sensor_height = 0;
  int offset_x = 0;  // the window's top-left pixel on the sensor
  int offset_y = 0;

  bool whole_sensor() const { return sensor_width == 0; }
  // A window of `width` x `height` centred on a sensor of `sensor_width` x `sensor_height`.
  static SensorWindow Centred(int width, int height, int sensor_width, int sensor_height);
  friend bool operator==(const SensorWindow&, const SensorWindow&) = default;
};

// The most texels along a side of a sample: larger than any lab's grid, small enough that nothing
// allocates on a typo's behalf (session.json's sample.texels_x/y, `process --texels`).
inline constexpr int kMaxTexelsPerSide = 16384;

inline constexpr double kNotNoted = std::numeric_limits<double>::quiet_NaN();

struct RigCamera {
  std::string id;       // the --camera that took the session, e.g. "v4l2:/dev/video0"
  std::string model;
  int width = 0, height = 0, channels = 0, bit_depth = 0;  // of the stored images; 0: not known
  std::string response;  // linear | srgb; empty: not noted
  SensorWindow sensor;
};

struct RigMonitor {
  std::string id;
  int width_px = 0, height_px = 0;
  double gamma = 0.0;
  double pixel_pitch_m = 0.0;
  double distance_m = 0.0;             // the monitor plane behind the sample plane
  double orientation_deg = kNotNoted;  // which way the screen lies (docs/calibration-format.md)
  double black_level = kNotNoted;      // luminance of level 0 as a fraction of white
  std::string emission;                // isotropic | lambertian | lcd; empty: not noted
  std::string polarisation;            // none | linear:DEG (docs/capture.md); empty: not noted
};

// rig.monitor.polarisation parsed: "none" or empty (unpolarised, or not noted), or "linear:DEG"
// (the field's angle from the screen's pixel x axis toward its top, counter-clockwise seen from
// the sample). Throws svbtdf::Error(kInvalidInput) naming `source` for anything else.
struct PolarisationNote {
  bool linear = false;
  double angle_deg = 0.0;
};
PolarisationNote ParsePolarisationNote(const std::string& spec, const std::string& source);

struct RigDots {
  int cols = 0, rows = 0;
  double radius_px = 0.0;
  std::vector<std::pair<double, double>> positions_px;  // dot q's centre pixel, row-major
  std::optional<std::vector<int>> fiducials;             // the dots of the fiducials capture
};

struct RigBoard {
  std::string spec;  // e.g. "chessboard:9x6:25"; empty: not noted
  int views = 0;
};

struct RigSample {
  double width_m = 0.0, height_m = 0.0;
  int texels_x = 0, texels_y = 0;  // the texel grid for processing; 0: processing chooses
  double eta = 0.0;                // relative index of refraction; 0: not known
};

struct RigDescription {
  RigCamera camera;
  RigMonitor monitor;
  RigDots dots;
  RigBoard board;
  RigBoard sample_plane_board;  // the board laid in the sample holder; empty spec: `board`
  RigSample sample;
  std::vector<double> exposures_s;
  nlohmann::json acquisition_plan;  // what `svbtdf acquire` ran (docs/capture.md); null if none
  nlohmann::json simulated;         // preset, seed and truth of a simulated session; null if none
  nlohmann::json others = nlohmann::json::object();  // keys this version does not know, kept
};

// Parses session.json's `rig`; svbtdf::Error(kFormat) naming `source` and the key for a field of
// the wrong type or a sensor window that is not [x, y].
RigDescription ParseRigDescription(const nlohmann::json& rig, const std::string& source);

// The `rig` object: the known fields that are set (non-zero, non-empty, not NaN), plus `others`.
nlohmann::json ToJson(const RigDescription& rig);

}  // namespace svbtdf::session
