#include "svbtdf/model/hemicube.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "svbtdf/common/error.h"

namespace svbtdf::model {
namespace {

// Integral of the solid angle over [0, a] x [0, b] of a plane at unit distance, signed: the
// rectangle [a0, a1] x [b0, b1] subtends F(a1,b1) - F(a0,b1) - F(a1,b0) + F(a0,b0).
double RectangleSolidAnglePrimitive(double a, double b) { return std::atan(a * b / std::sqrt(a * a + b * b + 1.0)); }

}  // namespace

Hemicube::Hemicube(int resolution) : n_(resolution) {
  if (resolution < 4 || resolution % 2 != 0 || resolution > 4096) {
    common::ThrowInvalidInput("hemicube resolution", "must be an even number from 4 to 4096, got " + std::to_string(resolution));
  }
  const int cells = num_cells();
  centers_.resize(cells);
  solid_angles_.resize(cells);
  neighbours_.resize(cells);
  mirrored_.resize(cells);
  const double step = 2.0 / n_;
  for (int c = 0; c < cells; ++c) {
    const FacePosition p = Position(c);
    const double a0 = -1.0 + step * p.u;
    const double b0 = p.face == 0 ? -1.0 + step * p.v : step * p.v;
    centers_[c] = FacePoint(p.face, a0 + 0.5 * step, b0 + 0.5 * step);
    solid_angles_[c] = FaceRectangleSolidAngle(p.face, a0, a0 + step, b0, b0 + step);
    neighbours_[c] = {Step(p.face, p.u, p.v, -1, 0), Step(p.face, p.u, p.v, 1, 0), Step(p.face, p.u, p.v, 0, -1),
                      Step(p.face, p.u, p.v, 0, 1)};
    if (p.face == 0) {
      mirrored_[c] = CellAt(0, n_ - 1 - p.u, n_ - 1 - p.v);
    } else {
      static constexpr int kOpposite[5] = {0, 2, 1, 4, 3};
      mirrored_[c] = CellAt(kOpposite[p.face], n_ - 1 - p.u, p.v);
    }
  }
}

Hemicube::FacePosition Hemicube::Position(int cell) const {
  if (cell < n_ * n_) return {0, cell % n_, cell / n_};
  const int side = cell - n_ * n_;
  const int per_face = n_ * (n_ / 2);
  const int local = side % per_face;
  return {1 + side / per_face, local % n_, local / n_};
}

int Hemicube::CellAt(int face, int u, int v) const {
  if (face == 0) return v * n_ + u;
  return n_ * n_ + (face - 1) * n_ * (n_ / 2) + v * n_ + u;
}

bool Hemicube::IsHorizon(int cell) const {
  const FacePosition p = Position(cell);
  return p.face != 0 && p.v == 0;
}

int Hemicube::FaceOf(const Vec3& d) {
  const double ax = std::abs(d.x()), ay = std::abs(d.y());
  if (d.z() >= ax && d.z() >= ay) return 0;
  if (ax >= ay) return d.x() > 0 ? 1 : 2;
  return d.y() > 0 ? 3 : 4;
}

Vec2 Hemicube::FaceCoordinates(int face, const Vec3& d) {
  switch (face) {
    case 0:
      return {d.x() / d.z(), d.y() / d.z()};
    case 1:
    case 2: {
      const double ax = std::abs(d.x());
      return {d.y() / ax, std::max(0.0, d.z()) / ax};
    }
    default: {
      const double ay = std::abs(d.y());
      return {d.x() / ay, std::max(0.0, d.z()) / ay};
    }
  }
}

Vec3 Hemicube::FacePoint(int face, double a, double b) const {
  switch (face) {
    case 0:
      return Vec3(a, b, 1.0).normalized();
    case 1:
      return Vec3(1.0, a, b).normalized();
    case 2:
      return Vec3(-1.0, a, b).normalized();
    case 3:
      return Vec3(a, 1.0, b).normalized();
    default:
      return Vec3(a, -1.0, b).normalized();
  }
}

double Hemicube::FaceRectangleSolidAngle(int face, double a0, double a1, double b0, double b1) const {
  return RectangleSolidAnglePrimitive(a1, b1) - RectangleSolidAnglePrimitive(a0, b1) -
         RectangleSolidAnglePrimitive(a1, b0) + RectangleSolidAnglePrimitive(a0, b0);
}

Vec3 Hemicube::CellPoint(int cell, double fu, double fv) const {
  const FacePosition p = Position(cell);
  const double step = 2.0 / n_;
  const double a = -1.0 + step * (p.u + fu);
  const double b = p.face == 0 ? -1.0 + step * (p.v + fv) : step * (p.v + fv);
  return FacePoint(p.face, a, b);
}

int Hemicube::CellOf(const Vec3& dir) const {
  const int face = FaceOf(dir);
  const Vec2 ab = FaceCoordinates(face, dir);
  const int u = std::clamp(static_cast<int>(std::floor((ab.x() + 1.0) * 0.5 * n_)), 0, n_ - 1);
  const double up = face == 0 ? (ab.y() + 1.0) * 0.5 * n_ : ab.y() * 0.5 * n_;
  const int v = std::clamp(static_cast<int>(std::floor(up)), 0, FaceHeight(face) - 1);
  return CellAt(face, u, v);
}

int Hemicube::Step(int face, int u, int v, int du, int dv) const {
  const int w = FaceWidth(face), h = FaceHeight(face);
  const int nu = u + du, nv = v + dv;
  if (nu >= 0 && nu < w && nv >= 0 && nv < h) return CellAt(face, nu, nv);
  const int top_row = n_ / 2 - 1, last = n_ - 1;
  if (face == 0) {  // off the top face onto the top row of a side
    if (nu < 0) return CellAt(2, v, top_row);
    if (nu >= n_) return CellAt(1, v, top_row);
    if (nv < 0) return CellAt(4, u, top_row);
    return CellAt(3, u, top_row);
  }
  if (nv < 0) return -1;  // below the horizon
  if (nv >= h) {          // up onto the top face
    switch (face) {
      case 1: return CellAt(0, last, u);
      case 2: return CellAt(0, 0, u);
      case 3: return CellAt(0, u, last);
      default: return CellAt(0, u, 0);
    }
  }
  // Across onto the adjacent side face, same height.
  if (nu >= w) {
    switch (face) {
      case 1: return CellAt(3, last, v);  // y = x:   +y's across x/y = +1
      case 2: return CellAt(3, 0, v);     // y = -x:  +y's across = -1
      case 3: return CellAt(1, last, v);  // x = y:   +x's across y/x = +1
      default: return CellAt(1, 0, v);    // x = -y:  +x's across = -1
    }
  }
  switch (face) {
    case 1: return CellAt(4, last, v);    // y = -x:  -y's across x/|y| = +1
    case 2: return CellAt(4, 0, v);       // y = x<0: -y's across = -1
    case 3: return CellAt(2, last, v);    // x = -y:  -x's across y/|x| = +1
    default: return CellAt(2, 0, v);      // x = y<0: -x's across = -1
  }
}

Hemicube::Weights Hemicube::Interpolation(const Vec3& dir) const {
  const int face = FaceOf(dir);
  const Vec2 ab = FaceCoordinates(face, dir);
  // Continuous coordinates in cell units, relative to the cell centres.
  const double s = (ab.x() + 1.0) * 0.5 * n_ - 0.5;
  const double t = (face == 0 ? (ab.y() + 1.0) * 0.5 * n_ : ab.y() * 0.5 * n_) - 0.5;
  const int i0 = static_cast<int>(std::floor(s)), j0 = static_cast<int>(std::floor(t));
  const double fs = s - i0, ft = t - j0;
  const int w = FaceWidth(face), h = FaceHeight(face);
  Weights result{};
  double total = 0.0;
  int count = 0;
  for (int dj = 0; dj < 2; ++dj) {
    for (int di = 0; di < 2; ++di) {
      const double weight = (di ? fs : 1.0 - fs) * (dj ? ft : 1.0 - ft);
      const int ci = i0 + di, cj = j0 + dj;
      const int ii = std::clamp(ci, 0, w - 1), jj = std::clamp(cj, 0, h - 1);
      const int du = ci - ii, dv = cj - jj;
      int cell = -1;
      if (du == 0 && dv == 0) {
        cell = CellAt(face, ii, jj);
      } else if (du == 0 || dv == 0) {
        cell = Step(face, ii, jj, du, dv);  // one seam away (or below the horizon: -1)
      }                                      // both: a cube corner, no cell
      if (cell < 0 || weight <= 0.0) continue;
      result[count++] = {cell, weight};
      total += weight;
    }
  }
  // Unused entries are (0, 0.0): a valid cell with no weight, so callers may index with it.
  if (total <= 0.0) return {std::pair<int, double>{CellOf(dir), 1.0}, {0, 0.0}, {0, 0.0}, {0, 0.0}};
  for (int k = 0; k < count; ++k) result[k].second /= total;
  for (int k = count; k < 4; ++k) result[k] = {0, 0.0};
  return result;
}

}  // namespace svbtdf::model
