#include "svbtdf/session/rig.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <type_traits>

#include "svbtdf/common/error.h"

namespace svbtdf::session {
namespace {

using nlohmann::json;

// Larger than any camera or monitor a lab has, small enough that products of two fit an int64
// and that nothing allocates on a typo's behalf.
constexpr int kMaxPixels = 65535;

// Reads the optional fields of one object of the rig, naming `where` (e.g. "rig.camera") in errors.
class Fields {
 public:
  // The fields of `object`, none when it is null.
  Fields(const json* object, std::string where, const std::string& source)
      : object_(object), where_(std::move(where)), source_(source) {}

  // The fields of member `key`, which must be an object when present.
  Fields Member(const char* key) const {
    const json* member = Find(key);
    if (member && !member->is_object()) common::ThrowFormatError(source_, where_ + "." + key + " must be an object");
    return Fields(member, where_ + "." + key, source_);
  }

  // Sets *out to member `key` when present; false when absent.
  template <typename T>
  bool Read(const char* key, T* out) const {
    const json* member = Find(key);
    if (!member) return false;
    try {
      *out = member->get<T>();
    } catch (const json::exception&) {
      common::ThrowFormatError(source_, where_ + "." + key + " has the wrong type (" + member->dump() + ")");
    }
    return true;
  }
  // Read, then refuse a value outside [lo, hi] (and a fraction where a whole number is meant):
  // nonsense such as a camera 1e12 pixels wide or an eta of -1.5 would fail much later, unnamed.
  template <typename T>
  bool ReadInRange(const char* key, T* out, T lo, T hi) const {
    const json* member = Find(key);
    if (member && std::is_integral_v<T> && !member->is_number_integer()) {
      common::ThrowFormatError(source_, where_ + "." + key + " must be a whole number, got " + member->dump());
    }
    if (!Read(key, out)) return false;
    if (!(*out >= lo && *out <= hi)) {  // also refuses NaN
      std::ostringstream range;
      range << "[" << lo << ", " << hi << "]";
      common::ThrowFormatError(source_, where_ + "." + key + " is " + member->dump() + ", outside " + range.str());
    }
    return true;
  }
  void ReadBoard(const char* key, RigBoard* board) const {
    const Fields fields = Member(key);
    fields.Read("spec", &board->spec);
    fields.Read("views", &board->views);
  }

 private:
  const json* Find(const char* key) const {
    if (!object_ || !object_->contains(key) || object_->at(key).is_null()) return nullptr;
    return &object_->at(key);
  }

  const json* object_;
  std::string where_;
  const std::string& source_;
};

SensorWindow ReadSensor(const Fields& camera, const std::string& source) {
  const Fields sensor = camera.Member("sensor");
  SensorWindow window;
  sensor.ReadInRange("width", &window.sensor_width, 1, kMaxPixels);
  sensor.ReadInRange("height", &window.sensor_height, 1, kMaxPixels);
  std::vector<int> offset;
  sensor.Read("window_offset", &offset);
  if (window.sensor_width > 0 || !offset.empty()) {
    if (offset.size() != 2 || window.sensor_height <= 0) {
      common::ThrowFormatError(source, "has a malformed rig.camera.sensor",
                       "it needs width, height and window_offset [x, y]");
    }
    window.offset_x = offset[0];
    window.offset_y = offset[1];
  }
  return window;
}

// Sets `object[key]` when the value is known.
void Put(json& object, const char* key, const std::string& value) {
  if (!value.empty()) object[key] = value;
}
void Put(json& object, const char* key, int value) {
  if (value != 0) object[key] = value;
}
void Put(json& object, const char* key, double value) {
  if (value != 0.0 && !std::isnan(value)) object[key] = value;
}
void PutObject(json& object, const char* key, json value) {
  if (!value.empty()) object[key] = std::move(value);
}

json BoardToJson(const RigBoard& board) {
  json out = json::object();
  Put(out, "spec", board.spec);
  Put(out, "views", board.views);
  return out;
}

}  // namespace

SensorWindow SensorWindow::Centred(int width, int height, int sensor_width, int sensor_height) {
  return {sensor_width, sensor_height, (sensor_width - width) / 2, (sensor_height - height) / 2};
}

RigDescription ParseRigDescription(const json& rig, const std::string& source) {
  if (!rig.is_object()) common::ThrowFormatError(source, "rig must be an object");
  const Fields all(&rig, "rig", source);
  RigDescription d;

  const Fields camera = all.Member("camera");
  camera.Read("id", &d.camera.id);
  camera.Read("model", &d.camera.model);
  camera.ReadInRange("width", &d.camera.width, 1, kMaxPixels);
  camera.ReadInRange("height", &d.camera.height, 1, kMaxPixels);
  camera.ReadInRange("channels", &d.camera.channels, 1, 4);
  camera.ReadInRange("bit_depth", &d.camera.bit_depth, 1, 16);
  camera.Read("response", &d.camera.response);
  d.camera.sensor = ReadSensor(camera, source);

  const Fields monitor = all.Member("monitor");
  monitor.Read("id", &d.monitor.id);
  monitor.ReadInRange("width_px", &d.monitor.width_px, 1, kMaxPixels);
  monitor.ReadInRange("height_px", &d.monitor.height_px, 1, kMaxPixels);
  monitor.ReadInRange("gamma", &d.monitor.gamma, 0.1, 10.0);
  monitor.ReadInRange("pixel_pitch_m", &d.monitor.pixel_pitch_m, 1e-6, 0.01);
  monitor.ReadInRange("distance_m", &d.monitor.distance_m, 1e-4, 100.0);
  monitor.ReadInRange("orientation_deg", &d.monitor.orientation_deg, -360.0, 360.0);
  monitor.ReadInRange("black_level", &d.monitor.black_level, 0.0, 0.999);
  monitor.Read("emission", &d.monitor.emission);
  monitor.Read("polarisation", &d.monitor.polarisation);

  const Fields dots = all.Member("dots");
  dots.ReadInRange("cols", &d.dots.cols, 1, 100000);
  dots.ReadInRange("rows", &d.dots.rows, 1, 100000);
  dots.ReadInRange("radius_px", &d.dots.radius_px, 0.01, 1e5);
  dots.Read("positions_px", &d.dots.positions_px);
  if (std::vector<int> fiducials; dots.Read("fiducials", &fiducials)) d.dots.fiducials = std::move(fiducials);

  all.ReadBoard("board", &d.board);
  all.ReadBoard("sample_plane_board", &d.sample_plane_board);
  const Fields sample = all.Member("sample");
  sample.ReadInRange("width_m", &d.sample.width_m, 1e-6, 100.0);
  sample.ReadInRange("height_m", &d.sample.height_m, 1e-6, 100.0);
  sample.ReadInRange("texels_x", &d.sample.texels_x, 1, kMaxTexelsPerSide);
  sample.ReadInRange("texels_y", &d.sample.texels_y, 1, kMaxTexelsPerSide);
  sample.ReadInRange("eta", &d.sample.eta, 1.0 + 1e-9, 5.0);
  all.Read("exposures_s", &d.exposures_s);
  for (const double exposure : d.exposures_s) {
    if (!(exposure > 0.0 && exposure < 1e6)) {
      common::ThrowFormatError(source, "rig.exposures_s holds " + std::to_string(exposure) + "; exposures are > 0 seconds");
    }
  }
  if (rig.contains("acquisition_plan")) d.acquisition_plan = rig.at("acquisition_plan");
  if (rig.contains("simulated")) d.simulated = rig.at("simulated");
  for (const auto& [key, value] : rig.items()) {
    static const char* const kKnown[] = {"camera", "monitor", "dots", "board", "sample_plane_board",
                                         "sample", "exposures_s", "acquisition_plan", "simulated"};
    if (std::find(std::begin(kKnown), std::end(kKnown), key) == std::end(kKnown)) d.others[key] = value;
  }
  return d;
}

json ToJson(const RigDescription& d) {
  json rig = d.others.is_object() ? d.others : json::object();
  json camera = json::object();
  Put(camera, "id", d.camera.id);
  Put(camera, "model", d.camera.model);
  Put(camera, "width", d.camera.width);
  Put(camera, "height", d.camera.height);
  Put(camera, "channels", d.camera.channels);
  Put(camera, "bit_depth", d.camera.bit_depth);
  Put(camera, "response", d.camera.response);
  if (!d.camera.sensor.whole_sensor()) {
    const SensorWindow& s = d.camera.sensor;
    camera["sensor"] = {{"width", s.sensor_width}, {"height", s.sensor_height}, {"window_offset", {s.offset_x, s.offset_y}}};
  }
  PutObject(rig, "camera", camera);

  json monitor = json::object();
  Put(monitor, "id", d.monitor.id);
  Put(monitor, "width_px", d.monitor.width_px);
  Put(monitor, "height_px", d.monitor.height_px);
  Put(monitor, "gamma", d.monitor.gamma);
  Put(monitor, "pixel_pitch_m", d.monitor.pixel_pitch_m);
  Put(monitor, "distance_m", d.monitor.distance_m);
  if (!std::isnan(d.monitor.orientation_deg)) monitor["orientation_deg"] = d.monitor.orientation_deg;
  if (!std::isnan(d.monitor.black_level)) monitor["black_level"] = d.monitor.black_level;
  Put(monitor, "emission", d.monitor.emission);
  Put(monitor, "polarisation", d.monitor.polarisation);
  PutObject(rig, "monitor", monitor);

  json dots = json::object();
  Put(dots, "cols", d.dots.cols);
  Put(dots, "rows", d.dots.rows);
  Put(dots, "radius_px", d.dots.radius_px);
  if (!d.dots.positions_px.empty()) {
    json positions = json::array();
    for (const auto& [x, y] : d.dots.positions_px) positions.push_back({x, y});
    dots["positions_px"] = positions;
  }
  if (d.dots.fiducials) dots["fiducials"] = *d.dots.fiducials;
  PutObject(rig, "dots", dots);

  PutObject(rig, "board", BoardToJson(d.board));
  PutObject(rig, "sample_plane_board", BoardToJson(d.sample_plane_board));
  json sample = json::object();
  Put(sample, "width_m", d.sample.width_m);
  Put(sample, "height_m", d.sample.height_m);
  Put(sample, "texels_x", d.sample.texels_x);
  Put(sample, "texels_y", d.sample.texels_y);
  Put(sample, "eta", d.sample.eta);
  PutObject(rig, "sample", sample);
  if (!d.exposures_s.empty()) rig["exposures_s"] = d.exposures_s;
  if (!d.acquisition_plan.is_null()) rig["acquisition_plan"] = d.acquisition_plan;
  if (!d.simulated.is_null()) rig["simulated"] = d.simulated;
  return rig;
}

PolarisationNote ParsePolarisationNote(const std::string& spec, const std::string& source) {
  PolarisationNote note;
  if (spec.empty() || spec == "none") return note;
  char* end = nullptr;
  const double angle = spec.rfind("linear:", 0) == 0 ? std::strtod(spec.c_str() + 7, &end) : 0.0;
  if (end == nullptr || *end != '\0' || end == spec.c_str() + 7 || !std::isfinite(angle)) {
    common::ThrowInvalidInput(source, "must be none or linear:DEG (the field's angle from the screen's pixel x axis "
                                      "toward its top, degrees), got '" + spec + "'");
  }
  note.linear = true;
  note.angle_deg = angle;
  return note;
}

}  // namespace svbtdf::session
