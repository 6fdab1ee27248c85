#include "svbtdf/simulate/rig_file.h"

#include <algorithm>
#include <cmath>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/json.h"
#include "svbtdf/simulate/presets.h"

namespace svbtdf::simulate {
namespace {

using nlohmann::json;

class Fields : public common::JsonFields {
 public:
  Fields(const json& object, std::string source, std::string prefix, std::set<std::string> known)
      : JsonFields(object, std::move(source), std::move(prefix), known, "see docs/capture.md for the rig file", "rig file") {}
};

constexpr double kDegree = model::kPi / 180.0;

void ParseCamera(const json& object, const std::string& source, RigFile* file) {
  const Fields f(object, source, "camera.", {"width", "height", "fx", "fy", "cx", "cy", "distortion", "sensor_width",
                                             "sensor_height", "distance_mm", "theta_deg", "frame_time_s",
                                             "control_delay_frames", "bit_depth", "full_well", "read_noise", "response"});
  RigConfig& rig = file->rig;
  CameraIntrinsics& k = rig.intrinsics;
  const bool resized = f.Has("width") || f.Has("height");
  k.width = f.Integer("width", 16, 100000, k.width);
  k.height = f.Integer("height", 16, 100000, k.height);
  k.fx = f.Number("fx", 1.0, 1e7, k.fx);
  k.fy = f.Number("fy", 1.0, 1e7, f.Has("fx") ? k.fx : k.fy);
  // A new image size without a principal point puts it at the image's centre.
  k.cx = f.Number("cx", -1e5, 1e5, resized ? (k.width - 1) / 2.0 : k.cx);
  k.cy = f.Number("cy", -1e5, 1e5, resized ? (k.height - 1) / 2.0 : k.cy);
  if (f.Has("distortion")) {
    const json& d = f.Raw("distortion");
    if (!d.is_array() || d.size() != 5) f.Fail("camera.distortion", "must list k1, k2, p1, p2, k3");
    for (int c = 0; c < 5; ++c) k.distortion[c] = f.CheckNumber(d[c], "distortion", -1e3, 1e3);
  }
  const int sensor_width = f.Integer("sensor_width", 0, 100000, resized ? 0 : rig.window.sensor_width);
  const int sensor_height = f.Integer("sensor_height", 0, 100000, resized ? 0 : rig.window.sensor_height);
  if ((sensor_width > 0) != (sensor_height > 0)) f.Fail("camera.sensor_width", "and sensor_height go together (0: no window)");
  if (sensor_width > 0 && (sensor_width < k.width || sensor_height < k.height)) {
    f.Fail("camera.sensor_width", "the sensor must be at least the image's size");
  }
  rig.window = sensor_width > 0 ? SensorWindow::Centred(k.width, k.height, sensor_width, sensor_height) : SensorWindow{};
  if (f.Has("distance_mm") || f.Has("theta_deg")) {
    const model::Vec3 centre = rig.pose.Centre();
    const double distance = f.Number("distance_mm", 1.0, 1e5, 1000.0 * centre.norm()) / 1000.0;
    const double theta = f.Number("theta_deg", 0.0, 80.0, std::acos(centre.normalized().z()) / kDegree) * kDegree;
    rig.pose = RigConfig::PaperPose(distance, theta);
  }
  file->frame_time_s = f.Number("frame_time_s", 1e-4, 600.0, file->frame_time_s);
  file->control_delay_frames = f.Integer("control_delay_frames", 0, 100, file->control_delay_frames);
  rig.sensor.bit_depth = f.Integer("bit_depth", 8, 16, rig.sensor.bit_depth);
  rig.sensor.full_well = f.Number("full_well", 1.0, 1e8, rig.sensor.full_well);
  rig.sensor.read_noise = f.Number("read_noise", 0.0, 1e5, rig.sensor.read_noise);
  rig.sensor.response = f.Text("response", rig.sensor.response);
  if (rig.sensor.response != "linear" && rig.sensor.response != "srgb") f.Fail("camera.response", "must be linear or srgb");
}

void ParseMonitor(const json& object, const std::string& source, RigConfig* rig) {
  const Fields f(object, source, "monitor.", {"distance_mm", "width_mm", "height_mm", "centre_mm", "pixel_pitch_mm",
                                              "orientation_deg", "tilt_deg", "gamma", "emission", "emission_exponent", "polarisation"});
  MonitorConfig& m = rig->monitor;
  m.distance = f.Number("distance_mm", 0.1, 1e4, 1000.0 * m.distance) / 1000.0;
  m.width = f.Number("width_mm", 1.0, 1e5, 1000.0 * m.width) / 1000.0;
  m.height = f.Number("height_mm", 1.0, 1e5, 1000.0 * m.height) / 1000.0;
  if (f.Has("centre_mm")) {
    const auto [x, y] = f.Pair("centre_mm", -1e5, 1e5);
    m.centre = model::Vec2(x / 1000.0, y / 1000.0);
  }
  m.pixel_pitch = f.Number("pixel_pitch_mm", 1e-3, 10.0, 1000.0 * m.pixel_pitch) / 1000.0;
  m.orientation_deg = f.Number("orientation_deg", -360.0, 360.0, m.orientation_deg);
  m.tilt_deg = f.Number("tilt_deg", -29.0, 29.0, m.tilt_deg);
  m.gamma = f.Number("gamma", 0.1, 10.0, m.gamma);
  m.emission.kind = f.Text("emission", m.emission.kind);
  if (m.emission.kind != "isotropic" && m.emission.kind != "lambertian" && m.emission.kind != "lcd") {
    f.Fail("monitor.emission", "must be isotropic, lambertian or lcd");
  }
  m.emission.exponent = f.Number("emission_exponent", 1e-3, 100.0, m.emission.exponent);
  if (f.Has("polarisation")) {
    const std::string spec = f.Text("polarisation", "none");
    try {
      m.polarisation = Polarisation::Parse(spec, "monitor.polarisation");
    } catch (const common::Error&) {
      f.Fail("monitor.polarisation", "must be none or linear:DEG (the field's angle from the screen's pixel x axis "
                                     "toward its top, degrees)");
    }
  }
}

void ParseSample(const json& object, const std::string& source, RigFile* file) {
  const Fields f(object, source, "sample.", {"width_mm", "texels_x", "texels_y", "eta"});
  SampleConfig& s = file->rig.sample;
  s.width = f.Number("width_mm", 0.1, 1e4, 1000.0 * s.width) / 1000.0;
  s.texels_x = f.Integer("texels_x", 1, 100000, s.texels_x);
  s.texels_y = f.Integer("texels_y", 1, 100000, f.Has("texels_x") ? s.texels_x : s.texels_y);
  file->eta = f.Number("eta", 1.001, 4.0, file->eta);
}

RigFile ParseRigJson(const json& root, const std::string& source) {
  const Fields f(root, source, "", {"format", "version", "name", "preset", "camera", "monitor", "sample"});
  if (f.Text("format", "") != kRigFileFormat) f.Fail("format", std::string("must be \"") + kRigFileFormat + "\"");
  const int version = f.Integer("version", 0, 1000000);
  if (version != kRigFileVersion) {
    common::ThrowFormatError(source, "is a version " + std::to_string(version) + " rig file; this build reads version " +
                                         std::to_string(kRigFileVersion));
  }
  const std::string preset = f.Text("preset", "demo");
  const std::vector<std::string> names = PresetNames();
  if (std::find(names.begin(), names.end(), preset) == names.end()) {
    f.Fail("preset", "names no simulator preset ('" + preset + "')");
  }
  RigFile file = RigFileOfPreset(preset);
  if (f.Has("camera")) ParseCamera(f.Raw("camera"), source, &file);
  if (f.Has("monitor")) ParseMonitor(f.Raw("monitor"), source, &file.rig);
  if (f.Has("sample")) ParseSample(f.Raw("sample"), source, &file);
  try {
    Rig check(file.rig);  // the geometry as a whole: the sample in view, the dots on the monitor ...
  } catch (const common::Error& e) {
    common::ThrowFormatError(source, "describes an impossible rig: " + e.subject() + ": " + e.problem(), e.hint());
  }
  return file;
}

}  // namespace

RigFile RigFileOfPreset(const std::string& preset) {
  const SimulationPreset p = MakePreset(preset);
  RigFile file;
  file.preset = preset;
  file.rig = p.rig;
  file.eta = p.eta;
  return file;
}

RigFile ParseRigFile(const std::string& text, const std::string& source) {
  return common::ParseJsonWith(text, source, "see docs/capture.md for the rig file",
                               [&](const json& root) { return ParseRigJson(root, source); });
}

RigFile ReadRigFile(const std::filesystem::path& path) { return ParseRigFile(common::ReadTextFile(path), path.string()); }

}  // namespace svbtdf::simulate
