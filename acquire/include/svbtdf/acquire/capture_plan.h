#pragma once
// The capture plan of `svbtdf acquire` (docs/capture.md, version 1): which dots to show, at which
// exposures, how often, and which calibration captures to take. A plan expands into the ordered
// list of captures with exactly the session keys of docs/session-format.md, so that calibration
// and processing read acquired and simulated sessions alike.

#include <cstdint>
#include <limits>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "svbtdf/acquire/display.h"

namespace svbtdf::simulate {
struct SimulatedSetup;
}

namespace svbtdf::acquire {

inline constexpr int kCapturePlanVersion = 1;

// What has to be in front of the camera for a capture (the operator arranges it).
enum class Scene {
  kSample,         // the sample in its holder, monitor behind it (dot images, dark frames)
  kNoSample,       // sample and holder removed, the monitor seen directly (all_dots, flat_white)
  kBoardView,      // the calibration board held in view, at varied poses (board/vNN)
  kBoardInHolder,  // the board lying in the sample holder (sample_plane/vNN)
};

// What the lab writes down about its set-up, recorded in the session manifest (rig) as the
// nominal values calibration starts from (docs/session-format.md). 0 or empty = not given.
struct RigNotes {
  double monitor_distance_mm = 0.0;  // d: the monitor plane behind the sample plane
  std::string emission;              // isotropic | lambertian | lcd
  std::string board;                 // Zhang calibration board, e.g. "chessboard:9x6:25"
  std::string sample_plane_board;    // the board laid in the sample holder, when not `board`
  double sample_width_mm = 0.0, sample_height_mm = 0.0;
  int texels_x = 0, texels_y = 0;    // the texel grid for processing
  double eta = 0.0;                  // the sample's relative index of refraction, if known
  std::string camera_response;       // linear | srgb
  // Which way the screen lies (rig.monitor.orientation_deg, docs/calibration-format.md); NaN: not
  // noted. Calibration checks it against the fiducial capture.
  double monitor_orientation_deg = std::numeric_limits<double>::quiet_NaN();
  // The screen's polarisation, as a lab measures it with a polariser (docs/capture.md, "A
  // polarised monitor"): none, or linear:DEG (the field's angle from the screen's pixel x axis
  // toward its top); empty: not noted. Recorded in the manifest's rig.monitor.polarisation.
  std::string monitor_polarisation;
};

struct CapturePlan {
  std::string name;
  // Dot centres in monitor pixels, row-major over a cols x rows grid (dot q = row * cols + col).
  int dot_cols = 0, dot_rows = 0;
  std::vector<std::pair<double, double>> dots_px;
  double dot_radius_px = 2.0;
  double dot_intensity = 1.0;       // linear, in (0, 1]
  std::vector<double> exposures_s;  // the dot brackets; dark frames are taken at each
  double gain = 1.0;
  int repeats = 1;                  // dot images per dot and bracket
  double settle_s = 0.2;            // wait after the display has presented a pattern
  int dark_frames = 2;              // per bracket
  // Calibration captures: none unless asked for (a plan file's `calibration` object defaults to
  // one sample-plane view, all dots and flat white).
  int board_views = 0;
  int sample_plane_views = 0;
  bool all_dots = false;
  bool fiducials = false;           // fiducial_dots lit at once, at the all-dots exposure
  std::vector<int> fiducial_dots;   // session::FiducialDots(cols, rows) when fiducials are planned
  bool flat_white = false;
  double board_exposure_s = 0.0;
  double all_dots_exposure_s = 0.0;
  double flat_white_exposure_s = 0.0;
  double pixel_pitch_mm = 0.0;      // of the monitor; 0 = unknown (then mm units are refused)
  uint64_t bytes_per_image = 0;     // for the free-space check; 0 = estimate from the camera
  RigNotes rig;
};

// One capture of the expanded plan.
struct PlannedCapture {
  std::string key;
  Pattern pattern;
  double exposure_s = 0.0;
  Scene scene = Scene::kSample;
  int view = 0;  // board or sample-plane view number
};

// Parses a plan; every problem is svbtdf::Error(kFormat or kInvalidInput) naming `source` and the
// field. Never anything else, whatever the bytes.
CapturePlan ParseCapturePlan(const std::string& text, const std::string& source);
CapturePlan ReadCapturePlan(const std::filesystem::path& path);

// The resolved plan (explicit dot positions), as stored in the session manifest: two plans are
// the same plan exactly when these are equal.
nlohmann::json CapturePlanToJson(const CapturePlan& plan);

// The built-in plans, one per simulator preset: the captures `svbtdf simulate --preset NAME`
// makes (same keys, exposures and dots), so that an acquisition with them is calibrated and
// fitted like a simulation.
std::vector<std::string> PlanPresetNames();
CapturePlan MakePlanPreset(const std::string& name);
CapturePlan PlanFromSimulation(const simulate::SimulatedSetup& setup);

// The captures in the order they are taken: dark frames, board views, sample plane, all dots,
// flat white (grouped so that the operator changes the scene as rarely as possible), then the
// dots.
std::vector<PlannedCapture> ExpandPlan(const CapturePlan& plan);
std::vector<std::string> PlanKeys(const std::vector<PlannedCapture>& captures);

// What the operator is asked to do for a scene.
std::string SceneInstruction(Scene scene, int view);

}  // namespace svbtdf::acquire
