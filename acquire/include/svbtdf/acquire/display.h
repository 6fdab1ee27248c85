#pragma once
// The display-dot pattern generator: a monitor behind the sample that shows one white dot at a
// time (and the calibration patterns). The SDL2 implementation drives a real monitor; the
// headless one renders the same patterns into images for tests and for the simulated camera.

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

namespace svbtdf::acquire {

struct Pattern {
  enum class Kind { kBlack, kDot, kAllDots, kFlatWhite, kChessboard };
  Kind kind = Kind::kBlack;
  double x_px = 0.0, y_px = 0.0;  // dot centre in monitor pixels (kDot)
  double dot_radius_px = 2.0;     // kDot and kAllDots
  std::vector<std::pair<double, double>> all_dots_px;  // kAllDots
  double intensity = 1.0;         // linear emitted intensity in [0, 1]; gamma is applied by the display
  int board_cols = 9, board_rows = 6;  // inner corners, kChessboard
  double board_square_px = 80.0;       // kChessboard
};

// Whether showing `b` after `a` changes nothing on the screen (the capture loop then neither shows
// it again nor waits the settle time).
inline bool SamePattern(const Pattern& a, const Pattern& b) {
  return a.kind == b.kind && a.x_px == b.x_px && a.y_px == b.y_px && a.dot_radius_px == b.dot_radius_px &&
         a.intensity == b.intensity && a.all_dots_px == b.all_dots_px && a.board_cols == b.board_cols &&
         a.board_rows == b.board_rows && a.board_square_px == b.board_square_px;
}

struct DisplayInfo {
  std::string id;             // the --display argument that selects it, e.g. "sdl:1" or "sim"
  int width_px = 0, height_px = 0;
  double pixel_pitch_mm = 0.0;  // 0 when unknown
  double gamma = 2.2;
};

// Seconds of std::chrono::steady_clock (CLOCK_MONOTONIC on Linux): the clock presentation times
// are given in and the capture loop waits on.
inline double MonotonicSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// When a pattern reached the screen, as Psychtoolbox's Screen('Flip') reports its stimulus onset.
struct Presentation {
  // MonotonicSeconds() of the refresh that first shows the pattern. A display whose pipeline
  // delays what it is given (a TV's processing, a compositor's extra buffer) reports a time after
  // Show returns: the capture loop waits until then, plus the settle time.
  double presented_s = 0.0;
  int missed_frames = 0;       // refreshes the swap came late by (0: on the first vsync)
  bool vsync_aligned = false;  // the time is that of a vsync-locked swap, not merely of Show returning
};

class Display {
 public:
  virtual ~Display() = default;
  virtual DisplayInfo Info() const = 0;
  // Shows the pattern and says when it was (or will be) presented; the caller waits until
  // presented_s plus the plan's settle time before capturing.
  virtual Presentation Show(const Pattern& pattern) = 0;
};

}  // namespace svbtdf::acquire
