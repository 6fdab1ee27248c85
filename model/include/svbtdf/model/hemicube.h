#pragma once
// The hemicube parameterisation of the upper hemisphere (docs/hemicube.md), used for NDF tables
// over half vectors h and for BTDF slices over light directions (flipped with FlipZ).
//
// Face 0 is the top of a cube, z = 1 with (x, y) in [-1, 1]^2, split into N x N cells. Faces 1-4
// are the upper halves of the sides x = +1, x = -1, y = +1, y = -1, each split into N cells
// across and N/2 cells up (z from 0 to 1). N is the resolution (the paper uses 32). A side cell in
// row 0 touches the horizon.
//
//   cell index: top        j * N + i                         i along x, j along y
//               side f     N^2 + (f - 1) N (N/2) + k N + m   m across, k up from the horizon
//   side "across" coordinate: +x: y/x   -x: y/|x|   +y: x/y   -y: x/|y|

#include <array>
#include <utility>
#include <vector>

#include "svbtdf/model/vec.h"

namespace svbtdf::model {

class Hemicube {
 public:
  // Throws svbtdf::Error(kInvalidInput) unless resolution is even and >= 4.
  explicit Hemicube(int resolution);

  int resolution() const { return n_; }
  int num_cells() const { return n_ * n_ + 4 * n_ * (n_ / 2); }

  // The cell containing direction `dir` (dir.z >= 0, any length).
  int CellOf(const Vec3& dir) const;
  // Unit direction through the cell's centre on its face.
  Vec3 CellCenter(int cell) const { return centers_[cell]; }
  // Unit direction through the point at fractional position (fu, fv) in [0,1]^2 of the cell's
  // rectangle on its face (fu across / along x, fv up / along y).
  Vec3 CellPoint(int cell, double fu, double fv) const;
  // Exact solid angle of the cell.
  double CellSolidAngle(int cell) const { return solid_angles_[cell]; }

  // Bilinear interpolation between cell centres: up to four (cell, weight) pairs with weights
  // >= 0 summing to 1. Across a face seam the neighbouring face's cells take part; at the cube's
  // corners (where three faces meet) and below the horizon row the missing cell is dropped and
  // the others renormalised. Unused entries are (0, 0.0).
  using Weights = std::array<std::pair<int, double>, 4>;
  Weights Interpolation(const Vec3& dir) const;

  // The four edge-adjacent cells (-across, +across, -up, +up in the cell's face coordinates),
  // across seams where needed; -1 below the horizon. Symmetric: a lists b iff b lists a.
  std::array<int, 4> Neighbours(int cell) const { return neighbours_[cell]; }
  bool IsHorizon(int cell) const;
  // The cell holding (-h.x, -h.y, h.z) for h in `cell` (an involution).
  int MirroredCell(int cell) const { return mirrored_[cell]; }

  // The face (0 top, 1 +x, 2 -x, 3 +y, 4 -y) and the integer position of a cell on it.
  struct FacePosition {
    int face, u, v;  // top: u = i, v = j; sides: u = m (across), v = k (up)
  };
  FacePosition Position(int cell) const;
  int CellAt(int face, int u, int v) const;

 private:
  // Continuous face coordinates of a direction: top (x/z, y/z); sides (across, up).
  static int FaceOf(const Vec3& d);
  static Vec2 FaceCoordinates(int face, const Vec3& d);
  Vec3 FacePoint(int face, double a, double b) const;
  double FaceRectangleSolidAngle(int face, double a0, double a1, double b0, double b1) const;
  int FaceWidth(int face) const { return n_; }
  int FaceHeight(int face) const { return face == 0 ? n_ : n_ / 2; }
  // The cell reached by stepping from (face, u, v) to (u + du, v + dv), crossing a seam if needed;
  // -1 when there is none.
  int Step(int face, int u, int v, int du, int dv) const;

  int n_;
  std::vector<Vec3> centers_;
  std::vector<double> solid_angles_;
  std::vector<std::array<int, 4>> neighbours_;
  std::vector<int> mirrored_;
};

}  // namespace svbtdf::model
