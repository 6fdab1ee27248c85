#include "svbtdf/acquire/capture_plan.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/json.h"
#include "svbtdf/common/error.h"
#include "svbtdf/session/capture_key.h"
#include "svbtdf/session/fiducials.h"
#include "svbtdf/simulate/capture_render.h"
#include "svbtdf/simulate/presets.h"

namespace svbtdf::acquire {
namespace {

using nlohmann::json;

constexpr const char* kFormatName = "svbtdf-capture-plan";

// A plan's objects, read through the house's strict field reader.
class Fields : public common::JsonFields {
 public:
  Fields(const json& object, std::string source, std::string prefix, std::set<std::string> known)
      : JsonFields(object, std::move(source), std::move(prefix), known, "see docs/capture.md for the plan format", "plan") {}
};

constexpr double kMaxExposure = 3600.0;
constexpr double kMaxMonitorPx = 100000.0;
constexpr double kMaxCaptures = 1e6;

// Dots either as an explicit list or as a regular grid, in monitor pixels or millimetres.
void ParseDots(const json& object, const std::string& source, double pixel_pitch_mm, CapturePlan* plan) {
  const Fields f(object, source, "dots.", {"cols", "rows", "units", "pitch", "origin", "radius", "positions_px",
                                           "radius_px", "intensity"});
  plan->dot_cols = f.Integer("cols", 1, 1000);
  plan->dot_rows = f.Integer("rows", 1, 1000);
  plan->dot_intensity = f.Number("intensity", 1e-6, 1.0, 1.0);
  const size_t count = static_cast<size_t>(plan->dot_cols) * plan->dot_rows;
  if (f.Has("positions_px")) {
    const json& list = f.Raw("positions_px");
    if (!list.is_array() || list.size() != count) f.Fail("dots.positions_px", "must list cols x rows = " + std::to_string(count) + " [x, y] pairs");
    for (const json& p : list) {
      if (!p.is_array() || p.size() != 2) f.Fail("dots.positions_px", "must hold [x, y] pairs");
      plan->dots_px.emplace_back(f.CheckNumber(p[0], "positions_px", 0, kMaxMonitorPx),
                                 f.CheckNumber(p[1], "positions_px", 0, kMaxMonitorPx));
    }
    plan->dot_radius_px = f.Number("radius_px", 0.1, 1000.0);
    return;
  }
  const std::string units = f.Text("units", "px");
  if (units != "px" && units != "mm") f.Fail("dots.units", "must be \"px\" or \"mm\"");
  if (units == "mm" && !(pixel_pitch_mm > 0)) {
    f.Fail("dots.units", "is \"mm\" but monitor.pixel_pitch_mm is not given");
  }
  const double scale = units == "mm" ? 1.0 / pixel_pitch_mm : 1.0;  // to monitor pixels
  const auto pitch = f.Pair("pitch", 0.0, kMaxMonitorPx);
  const auto origin = f.Pair("origin", 0.0, kMaxMonitorPx);
  plan->dot_radius_px = f.Number("radius", 1e-6, 1000.0) * scale;
  if (plan->dot_radius_px < 0.1) f.Fail("dots.radius", "is below 0.1 monitor pixel");
  for (int row = 0; row < plan->dot_rows; ++row) {
    for (int col = 0; col < plan->dot_cols; ++col) {
      plan->dots_px.emplace_back((origin.first + col * pitch.first) * scale, (origin.second + row * pitch.second) * scale);
    }
  }
}

void ParseCalibration(const json& object, const std::string& source, CapturePlan* plan) {
  const Fields f(object, source, "calibration.", {"board_views", "board_exposure_s", "sample_plane_views", "all_dots",
                                                  "all_dots_exposure_s", "fiducials", "flat_white",
                                                  "flat_white_exposure_s"});
  plan->board_views = f.Integer("board_views", 0, 100, 0);
  if (plan->board_views > 0 && plan->board_views < 3) f.Fail("calibration.board_views", "must be 0 or at least 3 (Zhang calibration)");
  plan->sample_plane_views = f.Integer("sample_plane_views", 0, 20, 1);
  plan->all_dots = f.Flag("all_dots", true);
  plan->flat_white = f.Flag("flat_white", true);
  // The fiducial dots tell calibration which blob is which dot; they need the all-dots capture.
  plan->fiducials = plan->all_dots && f.Flag("fiducials", true);
  if (plan->fiducials) plan->fiducial_dots = session::FiducialDots(plan->dot_cols, plan->dot_rows);
  const bool boards = plan->board_views + plan->sample_plane_views > 0;
  plan->board_exposure_s = boards ? f.Number("board_exposure_s", 1e-7, kMaxExposure) : 0.0;
  plan->all_dots_exposure_s = plan->all_dots ? f.Number("all_dots_exposure_s", 1e-7, kMaxExposure) : 0.0;
  plan->flat_white_exposure_s = plan->flat_white ? f.Number("flat_white_exposure_s", 1e-7, kMaxExposure) : 0.0;
}

void ParseRigNotes(const json& object, const std::string& source, RigNotes* rig) {
  const Fields f(object, source, "rig.", {"monitor_distance_mm", "emission", "board", "sample_plane_board", "sample_width_mm",
                                          "sample_height_mm", "texels_x", "texels_y", "eta", "camera_response",
                                          "monitor_orientation_deg", "monitor_polarisation"});
  rig->monitor_distance_mm = f.Number("monitor_distance_mm", 0.0, 10000.0, 0.0);
  rig->emission = f.Text("emission", "");
  rig->monitor_polarisation = f.Text("monitor_polarisation", "");
  if (!rig->monitor_polarisation.empty()) {
    try {
      rig->monitor_polarisation = simulate::Polarisation::Parse(rig->monitor_polarisation, "").ToString();
    } catch (const common::Error&) {
      f.Fail("rig.monitor_polarisation", "must be none or linear:DEG (the field's angle from the screen's pixel x axis "
                                         "toward its top, degrees)");
    }
  }
  if (!rig->emission.empty() && rig->emission != "isotropic" && rig->emission != "lambertian" && rig->emission != "lcd") {
    f.Fail("rig.emission", "must be isotropic, lambertian or lcd");
  }
  rig->board = f.Text("board", "");
  rig->sample_plane_board = f.Text("sample_plane_board", "");
  rig->sample_width_mm = f.Number("sample_width_mm", 0.0, 10000.0, 0.0);
  rig->sample_height_mm = f.Number("sample_height_mm", 0.0, 10000.0, 0.0);
  rig->texels_x = f.Integer("texels_x", 0, 100000, 0);
  rig->texels_y = f.Integer("texels_y", 0, 100000, 0);
  rig->eta = f.Number("eta", 0.0, 10.0, 0.0);
  rig->camera_response = f.Text("camera_response", "");
  if (!rig->camera_response.empty() && rig->camera_response != "linear" && rig->camera_response != "srgb") {
    f.Fail("rig.camera_response", "must be linear or srgb");
  }
  if (f.Has("monitor_orientation_deg")) rig->monitor_orientation_deg = f.Number("monitor_orientation_deg", -360.0, 360.0);
}

CapturePlan ParsePlanJson(const json& root, const std::string& source) {
  const Fields f(root, source, "", {"format", "version", "name", "monitor", "dots", "exposures_s", "gain", "repeats",
                                    "settle_s", "dark_frames", "calibration", "bytes_per_image", "rig"});
  if (f.Text("format", "") != kFormatName) f.Fail("format", std::string("must be \"") + kFormatName + "\"");
  const int version = f.Integer("version", 0, 1000000);
  if (version != kCapturePlanVersion) {
    common::ThrowFormatError(source, "is a version " + std::to_string(version) + " capture plan; this build reads version " +
                                 std::to_string(kCapturePlanVersion));
  }
  CapturePlan plan;
  plan.name = f.Text("name", "");
  if (f.Has("monitor")) {
    const Fields m(f.Raw("monitor"), source, "monitor.", {"pixel_pitch_mm"});
    plan.pixel_pitch_mm = m.Number("pixel_pitch_mm", 1e-3, 10.0, 0.0);
  }
  ParseDots(f.Raw("dots"), source, plan.pixel_pitch_mm, &plan);
  const json& exposures = f.Raw("exposures_s");
  if (!exposures.is_array() || exposures.empty() || exposures.size() > 16) f.Fail("exposures_s", "must list 1 to 16 exposures");
  for (const json& e : exposures) plan.exposures_s.push_back(f.CheckNumber(e, "exposures_s", 1e-7, kMaxExposure));
  plan.gain = f.Number("gain", 1e-3, 1e4, 1.0);
  plan.repeats = f.Integer("repeats", 1, 100, 1);
  plan.settle_s = f.Number("settle_s", 0.0, 60.0, 0.2);
  plan.dark_frames = f.Integer("dark_frames", 0, 100, 2);
  if (f.Has("calibration")) ParseCalibration(f.Raw("calibration"), source, &plan);
  if (f.Has("rig")) ParseRigNotes(f.Raw("rig"), source, &plan.rig);
  plan.bytes_per_image = static_cast<uint64_t>(f.Number("bytes_per_image", 0.0, 1e12, 0.0));
  // Far beyond any real session (the paper's 40 x 40 dots x 3 brackets is 4800), and it keeps the
  // expanded plan in memory small.
  const double dot_captures = static_cast<double>(plan.dots_px.size()) * plan.exposures_s.size() * plan.repeats;
  if (dot_captures > kMaxCaptures) {
    f.Fail("dots", "with the exposures and repeats asks for " + std::to_string(static_cast<int64_t>(dot_captures)) +
                       " dot images, more than " + std::to_string(static_cast<int64_t>(kMaxCaptures)));
  }
  return plan;
}

Pattern DotPattern(const CapturePlan& plan, size_t q) {
  Pattern p;
  p.kind = Pattern::Kind::kDot;
  p.x_px = plan.dots_px[q].first;
  p.y_px = plan.dots_px[q].second;
  p.dot_radius_px = plan.dot_radius_px;
  p.intensity = plan.dot_intensity;
  return p;
}

}  // namespace

CapturePlan ParseCapturePlan(const std::string& text, const std::string& source) {
  return common::ParseJsonWith(text, source, "see docs/capture.md for the plan format",
                               [&](const json& root) { return ParsePlanJson(root, source); });
}

CapturePlan ReadCapturePlan(const std::filesystem::path& path) {
  return ParseCapturePlan(common::ReadTextFile(path), path.string());
}

json CapturePlanToJson(const CapturePlan& plan) {
  json positions = json::array();
  for (const auto& [x, y] : plan.dots_px) positions.push_back({x, y});
  json out = {
      {"format", kFormatName},
      {"version", kCapturePlanVersion},
      {"name", plan.name},
      {"monitor", {{"pixel_pitch_mm", plan.pixel_pitch_mm}}},
      {"dots", {{"cols", plan.dot_cols}, {"rows", plan.dot_rows}, {"positions_px", positions},
                {"radius_px", plan.dot_radius_px}, {"intensity", plan.dot_intensity}}},
      {"exposures_s", plan.exposures_s},
      {"gain", plan.gain},
      {"repeats", plan.repeats},
      {"settle_s", plan.settle_s},
      {"dark_frames", plan.dark_frames},
      {"calibration", {{"board_views", plan.board_views}, {"board_exposure_s", plan.board_exposure_s},
                       {"sample_plane_views", plan.sample_plane_views}, {"all_dots", plan.all_dots},
                       {"all_dots_exposure_s", plan.all_dots_exposure_s}, {"fiducials", plan.fiducials},
                       {"flat_white", plan.flat_white},
                       {"flat_white_exposure_s", plan.flat_white_exposure_s}}},
      {"bytes_per_image", plan.bytes_per_image},
      {"rig", {{"monitor_distance_mm", plan.rig.monitor_distance_mm}, {"emission", plan.rig.emission},
               {"board", plan.rig.board}, {"sample_plane_board", plan.rig.sample_plane_board},
               {"sample_width_mm", plan.rig.sample_width_mm},
               {"sample_height_mm", plan.rig.sample_height_mm}, {"texels_x", plan.rig.texels_x},
               {"texels_y", plan.rig.texels_y}, {"eta", plan.rig.eta}, {"camera_response", plan.rig.camera_response}}},
  };
  if (!std::isnan(plan.rig.monitor_orientation_deg)) out["rig"]["monitor_orientation_deg"] = plan.rig.monitor_orientation_deg;
  if (!plan.rig.monitor_polarisation.empty()) out["rig"]["monitor_polarisation"] = plan.rig.monitor_polarisation;
  return out;
}

std::vector<std::string> PlanPresetNames() { return simulate::PresetNames(); }

CapturePlan MakePlanPreset(const std::string& name) {
  const std::vector<std::string> names = PlanPresetNames();
  if (std::find(names.begin(), names.end(), name) == names.end()) {
    std::string known;
    for (const std::string& n : names) known += (known.empty() ? "" : ", ") + n;
    common::ThrowInvalidInput("--plan-preset", "unknown preset '" + name + "'", "use " + known + ", or write a plan file (--plan)");
  }
  // The simulator's default seed: its material decides the exposures PlanCapture picks.
  const std::unique_ptr<simulate::SimulatedSetup> setup = simulate::MakeSimulatedSetup(simulate::MakePreset(name), 1, 0);
  return PlanFromSimulation(*setup);
}

CapturePlan PlanFromSimulation(const simulate::SimulatedSetup& setup) {
  const simulate::RigConfig& config = setup.rig->config();
  const simulate::CaptureTruth& capture = setup.plan;
  CapturePlan plan;
  plan.name = setup.preset.name;
  plan.dot_cols = config.dots.cols;
  plan.dot_rows = config.dots.rows;
  for (const simulate::Dot& dot : setup.rig->dots()) plan.dots_px.emplace_back(dot.drawn_x, dot.drawn_y);
  plan.dot_radius_px = config.dots.radius_px;
  plan.dot_intensity = config.monitor.Luminance(config.dots.level);
  plan.exposures_s = capture.dot_exposures_s;
  plan.repeats = 1;
  plan.settle_s = 0.02;  // a real monitor needs more: see docs/capture.md
  plan.dark_frames = config.dark_frames;
  plan.board_views = static_cast<int>(capture.zhang_boards.size());
  plan.sample_plane_views = 1;
  plan.all_dots = plan.flat_white = plan.fiducials = true;
  plan.fiducial_dots = session::FiducialDots(plan.dot_cols, plan.dot_rows);
  plan.board_exposure_s = capture.board_exposure_s;
  plan.all_dots_exposure_s = capture.all_dots_exposure_s;
  plan.flat_white_exposure_s = capture.flat_exposure_s;
  plan.pixel_pitch_mm = config.monitor.pixel_pitch * 1000.0;
  plan.bytes_per_image = static_cast<uint64_t>(config.intrinsics.width) * config.intrinsics.height * 3 * 2;
  // What `svbtdf simulate` writes as the session's nominal rig.
  plan.rig.monitor_distance_mm = config.monitor.distance * 1000.0;
  plan.rig.emission = config.monitor.emission.kind;
  plan.rig.board = config.board.Spec();
  plan.rig.sample_plane_board = config.holder_board.Spec();
  plan.rig.sample_width_mm = config.sample.width * 1000.0;
  plan.rig.sample_height_mm = config.sample.height() * 1000.0;
  plan.rig.texels_x = config.sample.texels_x;
  plan.rig.texels_y = config.sample.texels_y;
  plan.rig.eta = setup.preset.eta;
  plan.rig.camera_response = config.sensor.response;
  plan.rig.monitor_orientation_deg = simulate::NominalOrientationDeg(config.monitor);
  // Noted only for a polarised screen, so that the presets' plans and manifests stay as they were.
  if (config.monitor.polarisation.linear()) plan.rig.monitor_polarisation = config.monitor.polarisation.ToString();
  return plan;
}

namespace {

session::CaptureCounts CountsOf(const CapturePlan& plan) {
  session::CaptureCounts counts;
  counts.brackets = static_cast<int>(plan.exposures_s.size());
  counts.dark_frames = plan.dark_frames;
  counts.board_views = plan.board_views;
  counts.sample_plane_views = plan.sample_plane_views;
  counts.all_dots = plan.all_dots;
  counts.fiducials = plan.fiducials;
  counts.flat_white = plan.flat_white;
  counts.dots = static_cast<int>(plan.dots_px.size());
  counts.repeats = plan.repeats;
  return counts;
}

// Some of the plan's dots lit at once.
Pattern DotsLit(const CapturePlan& plan, const std::vector<std::pair<double, double>>& dots_px) {
  Pattern pattern;
  pattern.kind = Pattern::Kind::kAllDots;
  pattern.all_dots_px = dots_px;
  pattern.dot_radius_px = plan.dot_radius_px;
  pattern.intensity = plan.dot_intensity;
  return pattern;
}

// What the display shows, the exposure and the scene of one capture of the plan.
PlannedCapture Planned(const CapturePlan& plan, const session::CaptureKey& key) {
  using session::CaptureKind;
  const Pattern black;  // boards are lit by the room, and dark frames see a black monitor
  switch (key.kind) {
    case CaptureKind::kDark:
      return {key.Format(), black, plan.exposures_s.at(key.bracket), Scene::kSample};
    case CaptureKind::kBoardView:
      return {key.Format(), black, plan.board_exposure_s, Scene::kBoardView, key.view};
    case CaptureKind::kSamplePlaneView:
      return {key.Format(), black, plan.board_exposure_s, Scene::kBoardInHolder, key.view};
    case CaptureKind::kAllDots:
      return {key.Format(), DotsLit(plan, plan.dots_px), plan.all_dots_exposure_s, Scene::kNoSample};
    case CaptureKind::kFiducials: {
      std::vector<std::pair<double, double>> fiducials_px;
      for (int q : plan.fiducial_dots) fiducials_px.push_back(plan.dots_px.at(q));
      return {key.Format(), DotsLit(plan, fiducials_px), plan.all_dots_exposure_s, Scene::kNoSample};
    }
    case CaptureKind::kFlatWhite: {
      Pattern white;
      white.kind = Pattern::Kind::kFlatWhite;
      return {key.Format(), white, plan.flat_white_exposure_s, Scene::kNoSample};
    }
    case CaptureKind::kDot:
      return {key.Format(), DotPattern(plan, key.dot), plan.exposures_s.at(key.bracket), Scene::kSample};
    case CaptureKind::kMonitorPoseView:
      break;
  }
  common::ThrowInvalidInput(plan.name, "plans a capture the acquisition cannot take: " + key.Format());
}

}  // namespace

std::vector<PlannedCapture> ExpandPlan(const CapturePlan& plan) {
  std::vector<PlannedCapture> list;
  for (const session::CaptureKey& key : session::CaptureOrder(CountsOf(plan))) list.push_back(Planned(plan, key));
  return list;
}

std::vector<std::string> PlanKeys(const std::vector<PlannedCapture>& captures) {
  std::vector<std::string> keys;
  keys.reserve(captures.size());
  for (const PlannedCapture& c : captures) keys.push_back(c.key);
  return keys;
}

std::string SceneInstruction(Scene scene, int view) {
  switch (scene) {
    case Scene::kSample:
      return "put the sample in its holder, monitor behind it, room dark";
    case Scene::kNoSample:
      return "remove the sample and its holder so that the camera sees the monitor directly";
    case Scene::kBoardView:
      return "hold the calibration board in view, pose " + std::to_string(view) +
             " (tilt it 20-40 degrees about a new axis; the whole board in the image)";
    case Scene::kBoardInHolder:
      return "lay the calibration board flat in the sample holder (view " + std::to_string(view) + ")";
  }
  return {};
}

}  // namespace svbtdf::acquire
