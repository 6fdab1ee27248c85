#include "svbtdf/model/beckmann.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "svbtdf/model/ndf_validation.h"

namespace svbtdf::model {
namespace {

constexpr double kInvSqrtPi = 0.56418958354775628695;

// Slopes (x, y) of the unit-roughness isotropic Beckmann surface, distributed as the slopes
// visible from a direction with polar cosine cos_theta (azimuth 0). Jakob 2014, "An Improved
// Visible Normal Sampling Routine for the Beckmann Distribution".
Vec2 SampleVisibleSlopesUnitRoughness(double cos_theta, const Vec2& u) {
  const double u1 = std::clamp(u.x(), 1e-12, 1.0 - 1e-12);
  const double u2 = std::clamp(u.y(), 1e-12, 1.0 - 1e-12);
  if (cos_theta > 0.9999999) {  // normal incidence: the visible slopes are the slopes
    const double r = std::sqrt(-std::log(1.0 - u1));
    const double phi = kTwoPi * u2;
    return {r * std::cos(phi), r * std::sin(phi)};
  }
  const double sin_theta = std::sqrt(std::max(0.0, 1.0 - cos_theta * cos_theta));
  const double tan_theta = sin_theta / cos_theta;
  const double cot_theta = 1.0 / tan_theta;
  // The x-slope CDF is written in the erf domain b = erf(x), where it is smooth and monotone:
  //   CDF(b) = norm (1 + b + tan_theta exp(-erfinv(b)^2) / sqrt(pi)).
  double a = -1.0;
  double c = std::erf(cot_theta);
  const double theta = std::acos(cos_theta);
  const double fit = 1.0 + theta * (-0.876 + theta * (0.4265 - 0.0594 * theta));
  double b = c - (1.0 + c) * std::pow(1.0 - u1, fit);
  const double norm = 1.0 / (1.0 + c + kInvSqrtPi * tan_theta * std::exp(-cot_theta * cot_theta));
  for (int iteration = 0; iteration < 100; ++iteration) {
    if (!(b >= a && b <= c)) b = 0.5 * (a + c);  // Newton left the bracket: bisect
    const double x = ErfInv(b);
    const double value = norm * (1.0 + b + kInvSqrtPi * tan_theta * std::exp(-x * x)) - u1;
    if (std::abs(value) < 1e-13) break;
    if (value > 0) {
      c = b;
    } else {
      a = b;
    }
    const double derivative = norm * (1.0 - x * tan_theta);
    b -= value / derivative;
    if (c - a < 1e-15) break;
  }
  return {ErfInv(b), ErfInv(2.0 * u2 - 1.0)};
}

}  // namespace

double ErfInv(double y) {
  if (y <= -1.0) return -std::numeric_limits<double>::infinity();
  if (y >= 1.0) return std::numeric_limits<double>::infinity();
  // Giles, "Approximating the erfinv function" (2010), single-precision branch as a first guess.
  double w = -std::log((1.0 - y) * (1.0 + y));
  double x;
  if (w < 5.0) {
    w -= 2.5;
    double p = 2.81022636e-08;
    p = 3.43273939e-07 + p * w;
    p = -3.5233877e-06 + p * w;
    p = -4.39150654e-06 + p * w;
    p = 0.00021858087 + p * w;
    p = -0.00125372503 + p * w;
    p = -0.00417768164 + p * w;
    p = 0.246640727 + p * w;
    p = 1.50140941 + p * w;
    x = p * y;
  } else {
    w = std::sqrt(w) - 3.0;
    double p = -0.000200214257;
    p = 0.000100950558 + p * w;
    p = 0.00134934322 + p * w;
    p = -0.00367342844 + p * w;
    p = 0.00573950773 + p * w;
    p = -0.0076224613 + p * w;
    p = 0.00943887047 + p * w;
    p = 1.00167406 + p * w;
    p = 2.83297682 + p * w;
    x = p * y;
  }
  for (int step = 0; step < 2; ++step) {  // Newton on erf(x) = y
    const double derivative = 2.0 * kInvSqrtPi * std::exp(-x * x);
    if (derivative <= 0) break;
    x -= (std::erf(x) - y) / derivative;
  }
  return x;
}

BeckmannNdf::BeckmannNdf(double alpha_x, double alpha_y) : alpha_x_(alpha_x), alpha_y_(alpha_y) {
  RequirePositiveRoughness("beckmann", alpha_x, alpha_y);
}

double BeckmannNdf::D(const Vec3& h) const {
  if (h.z() <= 0) return 0.0;
  const double cos2 = h.z() * h.z();
  const double exponent = (Square(h.x() / alpha_x_) + Square(h.y() / alpha_y_)) / cos2;
  return std::exp(-exponent) / (kPi * alpha_x_ * alpha_y_ * cos2 * cos2);
}

double BeckmannNdf::Lambda(const Vec3& v) const {
  const double tangential = std::sqrt(Square(alpha_x_ * v.x()) + Square(alpha_y_ * v.y()));
  if (v.z() <= 0) return std::numeric_limits<double>::infinity();
  if (tangential <= 0) return 0.0;
  const double a = v.z() / tangential;
  return 0.5 * (std::erf(a) - 1.0) + std::exp(-a * a) / (2.0 * a) * kInvSqrtPi;
}

double BeckmannNdf::G1(const Vec3& v, const Vec3& h) const {
  const Vec3 side_adjusted = v.z() < 0 ? Vec3(-v) : v;
  if (side_adjusted.dot(h) <= 0 || side_adjusted.z() <= 0) return 0.0;
  return 1.0 / (1.0 + Lambda(side_adjusted));
}

NormalSample BeckmannNdf::SampleVisibleNormal(const Vec3& v, const Vec2& u) const {
  const Vec3 stretched = Vec3(alpha_x_ * v.x(), alpha_y_ * v.y(), v.z()).normalized();
  const double phi = std::atan2(stretched.y(), stretched.x());
  const Vec2 slope = SampleVisibleSlopesUnitRoughness(stretched.z(), u);
  const double cos_phi = std::cos(phi), sin_phi = std::sin(phi);
  const double slope_x = alpha_x_ * (cos_phi * slope.x() - sin_phi * slope.y());
  const double slope_y = alpha_y_ * (sin_phi * slope.x() + cos_phi * slope.y());
  const Vec3 h = Vec3(-slope_x, -slope_y, 1.0).normalized();
  return {h, VisibleNormalPdf(v, h), 1.0};
}

double BeckmannNdf::VisibleNormalPdf(const Vec3& v, const Vec3& h) const {
  if (v.z() <= 0) return 0.0;
  return G1(v, h) * std::max(0.0, v.dot(h)) * D(h) / v.z();
}

}  // namespace svbtdf::model
