#pragma once
// The capture keys of a session (docs/session-format.md, "Capture keys") and the order in which
// captures are taken. This header is the one owner of that grammar: acquisition and the
// simulator format keys with it, calibration and processing parse them with it.
//
//   dark/eB/rN         dark frame N at exposure bracket B
//   board/vNN          Zhang calibration board view NN
//   sample_plane/vNN   the board lying in the sample holder
//   monitor_pose/vNN   a chessboard shown on the monitor (optional, not planned by the house)
//   all_dots/eB        every dot lit at once, sample removed
//   fiducials/eB       the fiducial dots lit at once, sample removed
//   flat_white/eB      the monitor fully white, sample removed
//   dot/qQQQQ/eB/rR    dot Q at bracket B, repeat R, through the sample

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace svbtdf::session {

enum class CaptureKind {
  kDark,
  kBoardView,
  kSamplePlaneView,
  kMonitorPoseView,
  kAllDots,
  kFiducials,
  kFlatWhite,
  kDot,
};

struct CaptureKey {
  CaptureKind kind = CaptureKind::kDot;
  int dot = 0;      // kDot: dot q, row-major over the grid
  int bracket = 0;  // kDark, kAllDots, kFiducials, kFlatWhite, kDot: exposure bracket
  int repeat = 0;   // kDark: frame number; kDot: repeat
  int view = 0;     // kBoardView, kSamplePlaneView, kMonitorPoseView

  static CaptureKey Dark(int bracket, int frame) { return {CaptureKind::kDark, 0, bracket, frame, 0}; }
  static CaptureKey BoardView(int view) { return {CaptureKind::kBoardView, 0, 0, 0, view}; }
  static CaptureKey SamplePlaneView(int view) { return {CaptureKind::kSamplePlaneView, 0, 0, 0, view}; }
  static CaptureKey AllDots(int bracket = 0) { return {CaptureKind::kAllDots, 0, bracket, 0, 0}; }
  static CaptureKey Fiducials(int bracket = 0) { return {CaptureKind::kFiducials, 0, bracket, 0, 0}; }
  static CaptureKey FlatWhite(int bracket = 0) { return {CaptureKind::kFlatWhite, 0, bracket, 0, 0}; }
  static CaptureKey Dot(int dot, int bracket, int repeat = 0) { return {CaptureKind::kDot, dot, bracket, repeat, 0}; }

  // "dot/q0012/e1/r0" and so on.
  std::string Format() const;
  // The key a string spells, or nothing when it follows none of the forms above (numbers must
  // be written as Format writes them: "dot/q12/e1/r0" is not a key).
  static std::optional<CaptureKey> Parse(std::string_view text);

  friend bool operator==(const CaptureKey&, const CaptureKey&) = default;
};

// The key's first path element ("dot", "board", ...): the kind's name in keys.
std::string_view KindName(CaptureKind kind);

// What a session captures, in counts: the plan of a capture without its exposures and patterns.
struct CaptureCounts {
  int brackets = 1;            // dot exposure brackets; dark frames are taken at each
  int dark_frames = 0;         // per bracket
  int board_views = 0;
  int sample_plane_views = 0;
  bool all_dots = false;
  bool fiducials = false;
  bool flat_white = false;
  int dots = 0;
  int repeats = 1;             // dot images per dot and bracket
};

// The captures in the order they are taken: dark frames, board views, sample plane, all dots,
// fiducials, flat white (grouped so that the operator changes the scene as rarely as possible),
// then every dot at every bracket. The one capture order of the house: a lab acquisition and
// the simulator both follow it.
std::vector<CaptureKey> CaptureOrder(const CaptureCounts& counts);

}  // namespace svbtdf::session
