#include "svbtdf/simulate/truth_io.h"

#include <nlohmann/json.hpp>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/json.h"
#include "svbtdf/common/error.h"

namespace svbtdf::simulate {
namespace {

using nlohmann::json;

json ToJson(const model::Vec3& v) { return {v.x(), v.y(), v.z()}; }
json ToJson(const model::Vec2& v) { return {v.x(), v.y()}; }
json ToJson(const model::Mat3& m) {
  return {{m(0, 0), m(0, 1), m(0, 2)}, {m(1, 0), m(1, 1), m(1, 2)}, {m(2, 0), m(2, 1), m(2, 2)}};
}
json ToJson(const BoardPose& pose, const std::vector<model::Vec3>& corners) {
  json out = {{"rotation", ToJson(pose.rotation)}, {"translation", ToJson(pose.translation)}};
  json list = json::array();
  for (const model::Vec3& c : corners) list.push_back(ToJson(c));
  out["corners_world"] = list;
  return out;
}

model::Vec3 Vec3From(const json& j) { return {j.at(0).get<double>(), j.at(1).get<double>(), j.at(2).get<double>()}; }
model::Vec2 Vec2From(const json& j) { return {j.at(0).get<double>(), j.at(1).get<double>()}; }
model::Mat3 Mat3From(const json& j) {
  model::Mat3 m;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) m(r, c) = j.at(r).at(c).get<double>();
  }
  return m;
}
BoardPose BoardFrom(const json& j) {
  BoardPose pose;
  pose.rotation = Mat3From(j.at("rotation"));
  pose.translation = Vec3From(j.at("translation"));
  return pose;
}

}  // namespace

void WriteRigTruth(const std::filesystem::path& path, const Rig& rig, const CaptureTruth& capture) {
  const RigConfig& config = rig.config();
  const CameraIntrinsics& k = config.intrinsics;
  json out;
  out["format"] = "svbtdf-rig-truth";
  out["version"] = kRigTruthVersion;
  out["preset"] = capture.preset;
  out["pattern"] = capture.pattern;
  out["seed"] = capture.seed;
  out["truth"] = capture.truth_kind;
  out["frame"] = "sample frame: sample in z = 0 centred on the origin, z toward the camera, "
                 "monitor behind it, its centre at z = -d; metres";
  out["camera"] = {
      {"fx", k.fx}, {"fy", k.fy}, {"cx", k.cx}, {"cy", k.cy},
      {"distortion", {k.distortion[0], k.distortion[1], k.distortion[2], k.distortion[3], k.distortion[4]}},
      {"distortion_model", "opencv k1 k2 p1 p2 k3"},
      {"rms_px", 0.0},
      {"width", k.width}, {"height", k.height},
      {"rotation", ToJson(config.pose.rotation)},
      {"translation", ToJson(config.pose.translation)},
      {"pose_convention", "x_cam = rotation * x_world + translation (OpenCV)"},
      {"centre", ToJson(rig.camera().Centre())},
      {"theta_deg", rig.CameraTheta() * 180.0 / model::kPi}};
  const CameraIntrinsics& sensor_k = rig.sensor_camera().intrinsics();
  out["camera"]["sensor"] = {{"width", sensor_k.width}, {"height", sensor_k.height},
                             {"window_offset", {config.window.offset_x, config.window.offset_y}},
                             {"cx", sensor_k.cx}, {"cy", sensor_k.cy}};
  const MonitorConfig& m = config.monitor;
  out["monitor"] = {{"distance", m.distance}, {"width", m.width}, {"height", m.height},
                    {"centre", ToJson(m.centre)}, {"pixel_pitch", m.pixel_pitch},
                    {"gamma", m.gamma}, {"black_level", m.black_level},
                    {"white_exitance", m.white_exitance},
                    {"emission", {{"kind", m.emission.kind}, {"exponent", m.emission.exponent}}},
                    {"orientation_deg", m.orientation_deg}, {"tilt_deg", m.tilt_deg}, {"mirrored", m.mirrored}};
  // Only a polarised screen is written, so that the presets' truths stay as they were.
  if (m.polarisation.linear()) {
    out["monitor"]["polarisation"] = {
        {"kind", m.polarisation.kind}, {"angle_deg", m.polarisation.angle_deg},
        {"convention", "the field along the screen's right (u) turned by angle_deg toward its top (-down), "
                       "counter-clockwise seen from the sample; each ray carries its transverse part"}};
  }
  // The screen's frame: monitor pixel coordinates (u, v) sit at origin + pitch (u right + v down).
  const MonitorFrame& frame = rig.monitor_frame();
  out["monitor"]["frame"] = {{"origin", ToJson(frame.origin)}, {"right", ToJson(frame.right)},
                             {"down", ToJson(frame.down)}, {"normal", ToJson(frame.normal)},
                             {"convention", "point(u, v) = origin + pixel_pitch (u right + v down); normal toward "
                                            "the sample; a physical screen has right x down = -normal"}};
  const SampleConfig& s = config.sample;
  out["sample"] = {{"width", s.width}, {"height", s.height()}, {"texels_x", s.texels_x},
                   {"texels_y", s.texels_y}, {"texel_pitch", s.texel_pitch()},
                   {"texel_convention", "texel (col, row) centred at (-width/2 + (col + 0.5) pitch, "
                                        "height/2 - (row + 0.5) pitch, 0)"}};
  json dots = json::array();
  for (const Dot& dot : rig.dots()) {
    dots.push_back({{"col", dot.col}, {"row", dot.row}, {"position", ToJson(dot.position)},
                    {"monitor_pixel", {dot.monitor_x, dot.monitor_y}},
                    {"intensity", dot.intensity}, {"radius", dot.radius}});
  }
  out["dots"] = {{"cols", config.dots.cols}, {"rows", config.dots.rows},
                 {"radius_px", config.dots.radius_px}, {"level", config.dots.level},
                 {"intensity_convention", "L_q: radiant intensity along the monitor normal; toward "
                                          "x it is L_q P(cos theta_e) (monitor.emission)"},
                 {"list", dots}};
  const SensorConfig& sensor = config.sensor;
  out["sensor"] = {{"sensitivity", sensor.sensitivity}, {"full_well", sensor.full_well},
                   {"read_noise", sensor.read_noise}, {"shot_noise", sensor.shot_noise},
                   {"dark_current", sensor.dark_current}, {"bit_depth", sensor.bit_depth},
                   {"response", sensor.response}, {"vignetting", sensor.vignetting},
                   {"black_offset", sensor.black_offset}};
  json zhang = json::array();
  for (const BoardPose& pose : capture.zhang_boards) zhang.push_back(ToJson(pose, BoardCorners(pose, config.board)));
  const BoardConfig& b = config.board;
  const BoardConfig& h = config.holder_board;
  out["board"] = {{"kind", "chessboard"}, {"inner_cols", b.inner_cols}, {"inner_rows", b.inner_rows},
                  {"square", b.square}, {"zhang_views", zhang}, {"zhang_views_image", "whole sensor"}};
  out["holder_board"] = {{"kind", "chessboard"}, {"inner_cols", h.inner_cols}, {"inner_rows", h.inner_rows},
                         {"square", h.square}, {"pose", ToJson(capture.holder_board, BoardCorners(capture.holder_board, h))}};
  out["exposures"] = {{"dots_s", capture.dot_exposures_s}, {"all_dots_s", capture.all_dots_exposure_s},
                      {"flat_s", capture.flat_exposure_s}, {"board_s", capture.board_exposure_s}};
  common::WriteTextAtomically(path, out.dump(2) + "\n", /*overwrite=*/false);
}

RigTruth ReadRigTruth(const std::filesystem::path& path) {
  RigTruth truth;
  try {
    const json in = common::ReadJsonFile(path);
    if (in.value("format", "") != "svbtdf-rig-truth") {
      common::ThrowFormatError(path.string(), "is not an svbtdf rig truth file (format key)");
    }
    truth.version = common::IntegerAt(in, "version", path.string());
    if (truth.version != kRigTruthVersion) {
      common::ThrowFormatError(path.string(), "has version " + std::to_string(truth.version) +
                       ", this build reads version " + std::to_string(kRigTruthVersion),
                       "re-run `svbtdf simulate` with this build");
    }
    const json& c = in.at("camera");
    truth.camera.fx = c.at("fx");
    truth.camera.fy = c.at("fy");
    truth.camera.cx = c.at("cx");
    truth.camera.cy = c.at("cy");
    truth.camera.width = c.at("width");
    truth.camera.height = c.at("height");
    for (int n = 0; n < 5; ++n) truth.camera.distortion[n] = c.at("distortion").at(n);
    truth.rms_px = c.at("rms_px");
    truth.pose.rotation = Mat3From(c.at("rotation"));
    truth.pose.translation = Vec3From(c.at("translation"));
    const json& m = in.at("monitor");
    truth.monitor.distance = m.at("distance");
    truth.monitor.width = m.at("width");
    truth.monitor.height = m.at("height");
    truth.monitor.centre = Vec2From(m.at("centre"));
    truth.monitor.pixel_pitch = m.at("pixel_pitch");
    truth.monitor.gamma = m.at("gamma");
    truth.monitor.black_level = m.at("black_level");
    truth.monitor.white_exitance = m.at("white_exitance");
    truth.monitor.emission.kind = m.at("emission").at("kind");
    truth.monitor.emission.exponent = m.at("emission").at("exponent");
    truth.monitor.orientation_deg = m.at("orientation_deg");
    truth.monitor.tilt_deg = m.at("tilt_deg");
    truth.monitor.mirrored = m.at("mirrored");
    if (m.contains("polarisation")) {  // absent: unpolarised
      truth.monitor.polarisation.kind = m.at("polarisation").at("kind");
      truth.monitor.polarisation.angle_deg = m.at("polarisation").at("angle_deg");
      if (truth.monitor.polarisation.kind != "linear" && truth.monitor.polarisation.kind != "none") {
        common::ThrowFormatError(path.string(), "monitor.polarisation.kind must be none or linear");
      }
    }
    const json& s = in.at("sample");
    truth.sample.width = s.at("width");
    truth.sample.texels_x = s.at("texels_x");
    truth.sample.texels_y = s.at("texels_y");
    for (const json& d : in.at("dots").at("list")) {
      Dot dot;
      dot.col = d.at("col");
      dot.row = d.at("row");
      dot.position = Vec3From(d.at("position"));
      dot.monitor_x = d.at("monitor_pixel").at(0);
      dot.monitor_y = d.at("monitor_pixel").at(1);
      dot.intensity = d.at("intensity");
      dot.radius = d.at("radius");
      truth.dots.push_back(dot);
    }
    const json& b = in.at("board");
    for (const json& view : b.at("zhang_views")) truth.capture.zhang_boards.push_back(BoardFrom(view));
    truth.capture.holder_board = BoardFrom(in.at("holder_board").at("pose"));
    const json& e = in.at("exposures");
    truth.capture.dot_exposures_s = e.at("dots_s").get<std::vector<double>>();
    truth.capture.all_dots_exposure_s = e.at("all_dots_s");
    truth.capture.flat_exposure_s = e.at("flat_s");
    truth.capture.board_exposure_s = e.at("board_s");
    truth.capture.seed = in.at("seed");
    truth.capture.preset = in.at("preset");
    truth.capture.pattern = in.value("pattern", std::string());  // older truths: the preset's
    truth.capture.truth_kind = in.at("truth");
  } catch (const json::exception& e) {
    common::ThrowFormatError(path.string(), std::string("cannot be read: ") + e.what(),
                     "it should be a rig.json written by `svbtdf simulate`");
  }
  return truth;
}

}  // namespace svbtdf::simulate
