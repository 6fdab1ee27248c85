#pragma once
// TEMPORARY isotropic GGX for development until ndf_factory.h lands. Not to be committed.
#include <cmath>
#include <memory>
#include "svbtdf/model/ndf.h"
namespace svbtdf {
class DevGgx final : public Ndf {
 public:
  explicit DevGgx(double a) : a_(a) {}
  std::string name() const override { return "devggx"; }
  double D(const Vec3& h) const override {
    if (h.z() <= 0) return 0;
    const double c2 = h.z() * h.z(), t2 = (1 - c2) / c2;
    const double k = a_ * a_ + t2;
    return a_ * a_ / (kPi * c2 * c2 * k * k);
  }
  double G1(const Vec3& v0, const Vec3& h) const override {
    const Vec3 v = v0.z() < 0 ? Vec3(-v0) : v0;
    if (v.dot(h) <= 0 || v.z() <= 0) return 0;
    const double c2 = v.z() * v.z(), t2 = std::max(0.0, 1 - c2) / c2;
    return 2 / (1 + std::sqrt(1 + a_ * a_ * t2));
  }
  NormalSample SampleVisibleNormal(const Vec3& v, const Vec2& u) const override {
    const Vec3 vh = Vec3(a_ * v.x(), a_ * v.y(), v.z()).normalized();
    const double phi = kTwoPi * u.x();
    const double z = (1 - u.y()) * (1 + vh.z()) - vh.z();
    const double r = std::sqrt(std::max(0.0, 1 - z * z));
    const Vec3 c(r * std::cos(phi), r * std::sin(phi), z);
    const Vec3 hs = c + vh;
    Vec3 h = Vec3(a_ * hs.x(), a_ * hs.y(), std::max(0.0, hs.z())).normalized();
    NormalSample s{h, VisibleNormalPdf(v, h), 1.0};
    return s;
  }
  double VisibleNormalPdf(const Vec3& v, const Vec3& h) const override {
    return G1(v, h) * std::max(0.0, v.dot(h)) * D(h) / v.z();
  }
  std::unique_ptr<Ndf> Clone() const override { return std::make_unique<DevGgx>(a_); }
 private:
  double a_;
};
}  // namespace svbtdf

namespace svbtdf {
// TEMPORARY Beckmann (sampled by D cos, weighted to the visible-normal density) until
// ndf_factory.h lands. Not to be kept.
class DevBeckmann final : public Ndf {
 public:
  explicit DevBeckmann(double a) : a_(a) {}
  std::string name() const override { return "devbeckmann"; }
  double D(const Vec3& h) const override {
    if (h.z() <= 0) return 0;
    const double c2 = h.z() * h.z(), t2 = (1 - c2) / c2;
    return std::exp(-t2 / (a_ * a_)) / (kPi * a_ * a_ * c2 * c2);
  }
  double G1(const Vec3& v0, const Vec3& h) const override {
    const Vec3 v = v0.z() < 0 ? Vec3(-v0) : v0;
    if (v.dot(h) <= 0 || v.z() <= 0) return 0;
    const double tan_v = std::sqrt(std::max(0.0, 1 - v.z() * v.z())) / v.z();
    if (tan_v == 0) return 1;
    const double a = 1 / (a_ * tan_v);
    const double lambda = (std::erf(a) - 1) / 2 + std::exp(-a * a) / (2 * a * std::sqrt(kPi));
    return 1 / (1 + lambda);
  }
  NormalSample SampleVisibleNormal(const Vec3& v, const Vec2& u) const override {
    const double t2 = -a_ * a_ * std::log(1 - u.x());
    const double cos_t = 1 / std::sqrt(1 + t2), sin_t = std::sqrt(std::max(0.0, 1 - cos_t * cos_t));
    const double phi = kTwoPi * u.y();
    const Vec3 h(sin_t * std::cos(phi), sin_t * std::sin(phi), cos_t);
    NormalSample s{h, D(h) * h.z(), 0.0};
    s.weight = G1(v, h) * std::max(0.0, v.dot(h)) / (v.z() * h.z());
    return s;
  }
  double VisibleNormalPdf(const Vec3& v, const Vec3& h) const override {
    return D(h) * h.z();
  }
  std::unique_ptr<Ndf> Clone() const override { return std::make_unique<DevBeckmann>(a_); }
 private:
  double a_;
};
}  // namespace svbtdf
