#pragma once
// Which blob of the all-dots image is which displayed dot (docs/calibration-format.md, "Dot
// identification").
//
// The monitor is a physical screen: its pixel coordinates (u, v) run right and down as seen from
// its front, so that, seen from the sample, a displayed point (u, v) lands near
//   xy = A(phi) pitch (u, v) + t,   A(phi) = Rot(phi) diag(1, -1)
// on the sample frame's plane z = -d, phi being the direction of the screen's u axis. A mirror
// image of the screen (a mirrored display mode, or positions written flipped) gives
// A = Rot(phi) instead, which no screen seen from its front can. A dot grid looks the same under
// its own symmetries (a half turn; a quarter turn and mirrors when square), so the blobs alone
// leave several candidates; the fiducial capture, which lights a subset that no symmetry maps onto
// itself, tells them apart. Nothing here assumes which way up the screen lies.

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace svbtdf::calib {

struct DisplayedGrid {
  std::vector<Eigen::Vector2d> monitor_px;  // centre of each dot in (u, v) monitor pixel coordinates
  double pixel_pitch_m = 0;
  double spacing_m = 0;                     // the smallest distance between neighbouring dots
  std::vector<bool> fiducial;               // lit in the fiducial capture; empty: none was captured
};

// One way the displayed grid can lie on the plane, and how well the blobs say it does.
struct GridCandidate {
  double orientation_deg = 0;  // phi, in [0, 360)
  bool mirrored = false;
  std::vector<int> blob_of_dot;  // per dot, the blob it was matched to, or -1
  int matched = 0;
  double rms_m = 0;              // of the matched blobs about the fitted map
  double fiducial_agreement = -1;  // fraction of matched dots whose fiducial state the image shows; -1: unknown
};

struct DotIdentification {
  GridCandidate chosen;
  // The best candidate that a symmetry of the grid or a mirror would have given instead, by
  // fiducial agreement (-1 when there was no other or no fiducial capture).
  double runner_up_agreement = -1;
  std::string identified_by;  // "fiducials" or "declared orientation"
};

// The 8 candidates (4 quarter turns from the blobs' lattice direction, each plain and mirrored),
// each matched to the blobs; `blob_lit` (per blob, lit in the fiducial image) scores them when
// the grid has fiducials. Best first by matched count, then fiducial agreement.
std::vector<GridCandidate> MatchGridCandidates(const std::vector<Eigen::Vector2d>& blob_xy,
                                               const std::vector<bool>& blob_lit, const DisplayedGrid& grid);

// Chooses the candidate: by the fiducials when the grid has them, else by `declared_orientation_deg`
// (rig.monitor.orientation_deg) among the physical ones. Throws svbtdf::Error(kFormat) naming
// `source` (the capture that decided) when the screen is mirrored, the fiducials fit no candidate
// or two alike, the declared orientation contradicts them, or nothing decides.
DotIdentification IdentifyDots(const std::vector<Eigen::Vector2d>& blob_xy, const std::vector<bool>& blob_lit,
                               const DisplayedGrid& grid, std::optional<double> declared_orientation_deg,
                               const std::string& source);

}  // namespace svbtdf::calib
