#pragma once
// TEMPORARY development binning until model/hemicube.h lands on main. Not to be committed.
#include <cmath>
#include <vector>
#include "svbtdf/model/vec.h"

namespace svbtdf {

class DevHemicube {
 public:
  explicit DevHemicube(int resolution) : n_(resolution) {}
  int num_cells() const { return 5 * n_ * n_ / 1 - 2 * n_ * n_; }  // n^2 + 4 * n * n/2
  // cells: top face n x n (u = x/z, v = y/z in [-1,1]); then 4 side faces n x n/2.
  int CellIndex(const Vec3& d) const {
    const double ax = std::abs(d.x()), ay = std::abs(d.y()), az = d.z();
    if (az >= ax && az >= ay) {
      return Clamp((d.x() / az + 1) / 2 * n_) + n_ * Clamp((d.y() / az + 1) / 2 * n_);
    }
    int face;
    double a, b, m;
    if (ax >= ay) { face = d.x() > 0 ? 0 : 1; m = ax; a = d.y(); } else { face = d.y() > 0 ? 2 : 3; m = ay; a = d.x(); }
    b = az / m;  // in [0,1)
    const int ia = Clamp((a / m + 1) / 2 * n_);
    int ib = static_cast<int>(b * (n_ / 2)); if (ib >= n_ / 2) ib = n_ / 2 - 1; if (ib < 0) ib = 0;
    return n_ * n_ + face * n_ * (n_ / 2) + ia + n_ * ib;
  }
  Vec3 CellPoint(int cell, double fu, double fv) const {
    if (cell < n_ * n_) {
      const double u = ((cell % n_) + fu) / n_ * 2 - 1, v = ((cell / n_) + fv) / n_ * 2 - 1;
      return Vec3(u, v, 1).normalized();
    }
    cell -= n_ * n_;
    const int face = cell / (n_ * (n_ / 2));
    const int r = cell % (n_ * (n_ / 2));
    const double a = ((r % n_) + fu) / n_ * 2 - 1, b = ((r / n_) + fv) / (n_ / 2);
    Vec3 d;
    switch (face) {
      case 0: d = Vec3(1, a, b); break;
      case 1: d = Vec3(-1, a, b); break;
      case 2: d = Vec3(a, 1, b); break;
      default: d = Vec3(a, -1, b); break;
    }
    return d.normalized();
  }
  double CellSolidAngle(int cell) const {
    const Vec3 a = CellPoint(cell, 0, 0), b = CellPoint(cell, 1, 0), c = CellPoint(cell, 1, 1), d = CellPoint(cell, 0, 1);
    auto tri = [](const Vec3& p, const Vec3& q, const Vec3& r) {
      return 2 * std::atan2(std::abs(p.dot(q.cross(r))), 1 + p.dot(q) + q.dot(r) + r.dot(p));
    };
    return tri(a, b, c) + tri(a, c, d);
  }

 private:
  Vec3 Unnormalised(int cell, double fu, double fv) const {
    if (cell < n_ * n_) {
      return Vec3(((cell % n_) + fu) / n_ * 2 - 1, ((cell / n_) + fv) / n_ * 2 - 1, 1);
    }
    cell -= n_ * n_;
    const int r = cell % (n_ * (n_ / 2));
    return Vec3(1, ((r % n_) + fu) / n_ * 2 - 1, ((r / n_) + fv) / (n_ / 2));
  }
  int Clamp(double x) const { int i = static_cast<int>(x); return i < 0 ? 0 : (i >= n_ ? n_ - 1 : i); }
  int n_;
};

using Hemicube = DevHemicube;

}  // namespace svbtdf
