#pragma once
// What a capture will be before it is taken (`svbtdf plan`, docs/capture.md "Planning a
// capture"): how many images, how long, how much disk, which angles the dots cover at the
// sample's centre and corners, and whether they are dense enough for a given roughness.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "svbtdf/acquire/capture_plan.h"
#include "svbtdf/simulate/rig_file.h"

namespace svbtdf::acquire {

// The time the capture loop spends, by cause (seconds). Operator steps (placing the sample,
// holding the board) are not counted.
struct CaptureDuration {
  double exposing_s = 0.0;   // every capture takes max(exposure, frame time)
  double settling_s = 0.0;   // settle_s after each new pattern
  double control_s = 0.0;    // frames discarded after each exposure change until it applies
  int patterns = 0;          // patterns shown
  int exposure_changes = 0;
  double total_s() const { return exposing_s + settling_s + control_s; }
};

// The dots seen from one point of the sample.
struct DotCoverage {
  std::string where;                 // "centre", "corner (-x, +y)", ...
  double min_incidence_deg = 0.0;    // the dots' angles from the sample normal
  double max_incidence_deg = 0.0;
  double straight_through_to_nearest_dot_deg = 0.0;  // how far the peak of a specular lobe falls from a dot
  bool straight_through_in_grid = false;  // the straight-through direction meets the screen inside the grid
  double reach_deg = 0.0;            // from the straight-through direction to the farthest dot
  double spacing_deg = 0.0;          // between neighbouring dots, around the straight-through direction
  double dot_radius_deg = 0.0;       // a dot's angular radius there
};

// A GGX lobe of the given roughness through the sample, as the dual-microfacet model transmits
// it toward the camera from the sample's centre.
struct LobeSampling {
  double roughness = 0.0;      // GGX alpha
  double width_deg = 0.0;      // full width at half maximum, over the incident direction
  double dots_across = 0.0;    // width / the dot spacing at the centre
  std::string verdict;         // "too sparse", "dots too large" or "ok"
};

struct CaptureForecast {
  std::string plan_name, rig_name;
  double exposure_scale = 1.0;  // what the plan's exposures were multiplied by (ScaleExposures)
  int64_t images = 0;
  int64_t dot_images = 0;
  int operator_steps = 0;      // scene changes the operator makes
  CaptureDuration duration;
  double frame_time_s = 0.0;
  int control_delay_frames = 0;
  uint64_t bytes = 0;          // acquire's own free-space estimate (EstimatedBytes)
  std::array<int, 2> image_size = {0, 0};
  std::array<int, 2> sensor_size = {0, 0};  // of the board views, when the images are a window
  double eta = 0.0;
  std::vector<DotCoverage> coverage;  // centre, then the four corners
  std::vector<LobeSampling> lobes;
};

// Fewer dots than this across a lobe's half-maximum width cannot resolve its shape.
inline constexpr double kMinDotsAcrossLobe = 3.0;

// The plan with every exposure (dots, dark frames and calibration captures) multiplied by the
// factor that makes its shortest dot exposure `shortest_s`: the brackets keep their ratios. The
// simulator's plans are in its own radiometric unit, not seconds; a lab sets its shortest dot
// exposure by looking at the brightest dot (docs/capture.md, "Exposures and brackets").
CapturePlan ScaleExposures(CapturePlan plan, double shortest_s, double* factor = nullptr);

// Throws svbtdf::Error(kInvalidInput) when a dot of the plan lies off the rig's monitor.
CaptureForecast ForecastCapture(const CapturePlan& plan, const simulate::RigFile& rig, const std::string& rig_name,
                                const std::vector<double>& roughnesses);

// The forecast as `svbtdf plan` prints it.
std::string FormatForecast(const CaptureForecast& forecast);

}  // namespace svbtdf::acquire
