#pragma once
// Small vector vocabulary shared by every module. Directions are unit Eigen vectors in the
// sample frame of docs/model.md: z is the macro normal and points toward the camera.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

namespace svbtdf::model {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

inline constexpr double kPi = std::numbers::pi;
inline constexpr double kTwoPi = 2.0 * std::numbers::pi;
inline constexpr double kInvPi = 1.0 / std::numbers::pi;

inline double Square(double x) { return x * x; }

// Flips a direction through the slab plane (z -> -z), e.g. to look a light direction up on a
// hemicube built over the upper hemisphere.
inline Vec3 FlipZ(const Vec3& v) { return {v.x(), v.y(), -v.z()}; }

// Unit direction from spherical angles (theta from +z, phi from +x toward +y).
inline Vec3 SphericalDirection(double theta, double phi) {
  const double s = std::sin(theta);
  return {s * std::cos(phi), s * std::sin(phi), std::cos(theta)};
}

// Two unit vectors completing `n` to a right-handed orthonormal frame (Duff et al. 2017).
inline void OrthonormalBasis(const Vec3& n, Vec3* t, Vec3* b) {
  const double sign = std::copysign(1.0, n.z());
  const double a = -1.0 / (sign + n.z());
  const double c = n.x() * n.y() * a;
  *t = Vec3(1.0 + sign * n.x() * n.x() * a, sign * c, -sign * n.x());
  *b = Vec3(c, sign + n.y() * n.y() * a, -n.y());
}

}  // namespace svbtdf::model
