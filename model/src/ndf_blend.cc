#include "svbtdf/model/ndf_blend.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "svbtdf/common/error.h"

namespace svbtdf::model {

void TabulatedNdfBlend::Add(const TabulatedNdf& ndf, double weight) {
  if (!std::isfinite(weight)) common::ThrowInvalidInput("NDF blend", "has a non-finite weight");
  if (weight == 0.0) return;
  if (count_ == kMaxComponents) {
    common::ThrowInvalidInput("NDF blend", "has more than " + std::to_string(kMaxComponents) + " components");
  }
  if (count_ > 0 && ndf.grid().resolution() != components_[0].ndf->grid().resolution()) {
    common::ThrowInvalidInput("NDF blend", "mixes hemicubes of different resolutions");
  }
  components_[count_++] = {&ndf, weight};
}

double TabulatedNdfBlend::D(const Vec3& h) const {
  if (h.z() <= 0 || count_ == 0) return 0.0;
  // One interpolation serves every component: they share the hemicube.
  const Hemicube::Weights corners = components_[0].ndf->grid().Interpolation(h);
  double d = 0;
  for (int j = 0; j < count_; ++j) {
    const std::vector<double>& ln_d = components_[j].ndf->ln_d();
    double ln = 0;
    for (const auto& [cell, w] : corners) ln += w * ln_d[cell];
    d += components_[j].weight * std::exp(ln);
  }
  return std::max(d, 0.0);
}

double TabulatedNdfBlend::SamplingMasses(const Vec3& v, std::array<double, kMaxComponents>& mass) const {
  double total = 0;
  for (int j = 0; j < count_; ++j) {
    const double weight = components_[j].weight;
    mass[j] = weight > 0 ? weight * components_[j].ndf->ProjectedArea(v) : 0.0;
    total += mass[j];
  }
  return total;
}

double TabulatedNdfBlend::G1(const Vec3& v, const Vec3& h) const {
  const Vec3 side_adjusted = v.z() < 0 ? Vec3(-v) : v;
  if (side_adjusted.dot(h) <= 0 || side_adjusted.z() <= 0) return 0.0;
  std::array<double, kMaxComponents> mass;
  const double area = SamplingMasses(side_adjusted, mass);
  return area > 0 ? std::min(1.0, side_adjusted.z() / area) : 1.0;
}

double TabulatedNdfBlend::VisibleNormalPdf(const Vec3& v, const Vec3& h) const {
  if (v.z() <= 0 || h.z() <= 0) return 0.0;
  std::array<double, kMaxComponents> mass;
  const double total = SamplingMasses(v, mass);
  if (!(total > 0)) return 0.0;
  double pdf = 0;
  for (int j = 0; j < count_; ++j) {
    if (mass[j] > 0) pdf += mass[j] / total * components_[j].ndf->VisibleNormalPdf(v, h);
  }
  return pdf;
}

NormalSample TabulatedNdfBlend::SampleVisibleNormal(const Vec3& v, const Vec2& u) const {
  std::array<double, kMaxComponents> mass;
  const double total = SamplingMasses(v, mass);
  if (!(total > 0)) throw common::Error(common::ErrorKind::kNumerical, "NDF blend", "has no component to sample");
  // u.x picks the component and, rescaled to [0, 1) within its share, drives its sampler.
  double pick = u.x() * total;
  int chosen = 0;
  for (int j = 0; j < count_; ++j) {
    if (mass[j] <= 0) continue;
    chosen = j;
    if (pick < mass[j]) break;
    pick -= mass[j];
  }
  const double reused = std::clamp(pick / mass[chosen], 0.0, std::nextafter(1.0, 0.0));
  const Vec3 h = components_[chosen].ndf->SampleVisibleNormal(v, {reused, u.y()}).h;
  const double pdf = VisibleNormalPdf(v, h);
  const double weight = pdf > 0 ? G1(v, h) * std::max(0.0, v.dot(h)) * D(h) / (v.z() * pdf) : 0.0;
  return {h, pdf, weight};
}

}  // namespace svbtdf::model
