#pragma once
// The fiducial capture of a session (docs/session-format.md, `fiducials/e0`): some of the dots
// lit at once, the sample removed. A regular dot grid looks the same turned by half a turn (by a
// quarter turn too when it is square) and in a mirror, so the all-dots image alone cannot tell
// which blob is which dot; the fiducial dots can, because no symmetry of the grid maps them onto
// themselves. Calibration reads the lit dots from the session (rig.dots.fiducials), so a lab may
// light any such set; FiducialDots is the set that `svbtdf acquire` and `svbtdf simulate` plan.

#include <vector>

namespace svbtdf::session {

// The maps q -> g(q) of dot indices (q = row * cols + col) under which the cols x rows grid goes
// onto itself: the identity first, then the mirrors and turns (8 for a square grid, 4 otherwise).
std::vector<std::vector<int>> GridSymmetries(int cols, int rows);

// The number of dots in which `lit` and its image under `symmetry` differ.
int SymmetryDistance(const std::vector<bool>& lit, const std::vector<int>& symmetry);

// About half of the dots, chosen by a fixed pseudo-random rule, so that every symmetry of the
// grid other than the identity changes about half of them (at least a quarter where the grid
// allows): a few misread dots cannot make one orientation look like another. Sorted dot indices.
std::vector<int> FiducialDots(int cols, int rows);

}  // namespace svbtdf::session
