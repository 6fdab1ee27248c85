#include "svbtdf/model/vmf_ndf.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include "svbtdf/common/error.h"

namespace svbtdf::model {
namespace {

constexpr int kThetaSteps = 32, kPhiSteps = 32;

// Quadrature nodes over the upper hemisphere in polar coordinates about `centre`, with radial
// nodes concentrated near it (r = pi s^2) so that sharp lobes are resolved at any kappa.
struct Nodes {
  std::vector<Vec3> directions;
  std::vector<double> weights;  // solid angle each node stands for
};

Nodes NodesAround(const Vec3& centre, int radial, int azimuth) {
  Nodes nodes;
  Vec3 t, b;
  OrthonormalBasis(centre, &t, &b);
  for (int a = 0; a < radial; ++a) {
    const double s = (a + 0.5) / radial, r = kPi * s * s;
    const double weight = std::sin(r) * 2.0 * kPi * s / radial * kTwoPi / azimuth;
    for (int k = 0; k < azimuth; ++k) {
      const double phi = kTwoPi * (k + 0.5) / azimuth;
      const Vec3 h = std::cos(r) * centre + std::sin(r) * (std::cos(phi) * t + std::sin(phi) * b);
      if (h.z() <= 0) continue;
      nodes.directions.push_back(h);
      nodes.weights.push_back(weight);
    }
  }
  return nodes;
}

}  // namespace

VmfNdf::VmfNdf(const Vec3& mean, double kappa) : mean_(mean.normalized()), kappa_(kappa) {
  if (!(kappa > 0 && kappa <= 1e5)) common::ThrowInvalidInput("kappa", "the vMF concentration must lie in (0, 1e5]");
  if (!mean.allFinite() || !(mean_.z() > 0)) common::ThrowInvalidInput("mean", "the vMF mean normal must have z > 0");
  // Normalisation on fine nodes; the projected-area table (for G1 and the sampler's pdf) on
  // coarser ones with D and the weights folded together.
  ln_norm_ = 0.0;  // D() below returns the unnormalised lobe until this is set
  const Nodes fine = NodesAround(mean_, 400, 128);
  double integral = 0;
  for (size_t k = 0; k < fine.directions.size(); ++k) integral += D(fine.directions[k]) * fine.directions[k].z() * fine.weights[k];
  ln_norm_ = std::log(integral);
  Nodes coarse = NodesAround(mean_, 96, 48);
  for (size_t k = 0; k < coarse.directions.size(); ++k) coarse.weights[k] *= D(coarse.directions[k]);
  area_.resize(static_cast<size_t>(kThetaSteps + 1) * kPhiSteps);
  for (int ti = 0; ti <= kThetaSteps; ++ti) {
    const double theta = std::min(0.5 * kPi * ti / kThetaSteps, 0.5 * kPi - 1e-6);
    for (int pi = 0; pi < kPhiSteps; ++pi) {
      const Vec3 v = SphericalDirection(theta, kTwoPi * pi / kPhiSteps);
      double area = 0;
      for (size_t k = 0; k < coarse.directions.size(); ++k) area += std::max(0.0, v.dot(coarse.directions[k])) * coarse.weights[k];
      area_[static_cast<size_t>(ti) * kPhiSteps + pi] = area;
    }
  }
}

double VmfNdf::D(const Vec3& h) const {
  if (h.z() <= 0) return 0.0;
  return std::exp(kappa_ * (mean_.dot(h) - 1.0) - ln_norm_);
}

double VmfNdf::ProjectedArea(const Vec3& v) const {
  const double theta = std::acos(std::clamp(v.z(), 0.0, 1.0));
  double phi = std::atan2(v.y(), v.x());
  if (phi < 0) phi += kTwoPi;
  const double t = theta / (0.5 * kPi) * kThetaSteps, p = phi / kTwoPi * kPhiSteps;
  const int t0 = std::min(static_cast<int>(t), kThetaSteps - 1);
  const int p0 = static_cast<int>(p) % kPhiSteps, p1 = (p0 + 1) % kPhiSteps;
  const double ft = t - t0, fp = p - std::floor(p);
  const auto a = [&](int ti, int pi) { return area_[static_cast<size_t>(ti) * kPhiSteps + pi]; };
  return (1 - ft) * ((1 - fp) * a(t0, p0) + fp * a(t0, p1)) + ft * ((1 - fp) * a(t0 + 1, p0) + fp * a(t0 + 1, p1));
}

double VmfNdf::G1(const Vec3& v, const Vec3& h) const {
  const Vec3 side_adjusted = v.z() < 0 ? Vec3(-v) : v;
  if (side_adjusted.dot(h) <= 0 || side_adjusted.z() <= 0) return 0.0;
  return std::min(1.0, side_adjusted.z() / ProjectedArea(side_adjusted));
}

double VmfNdf::VisibleNormalPdf(const Vec3& v, const Vec3& h) const {
  if (v.z() <= 0) return 0.0;
  return std::max(0.0, v.dot(h)) * D(h) / ProjectedArea(v);
}

Vec3 VmfNdf::SampleLobe(double u1, double u2) const {
  // w = cos of the angle to the mean, inverted stably for large kappa (Jakob 2012).
  const double w = 1.0 + std::log(u1 + (1.0 - u1) * std::exp(-2.0 * kappa_)) / kappa_;
  const double r = std::sqrt(std::max(0.0, 1.0 - w * w));
  Vec3 t, b;
  OrthonormalBasis(mean_, &t, &b);
  return w * mean_ + r * (std::cos(kTwoPi * u2) * t + std::sin(kTwoPi * u2) * b);
}

NormalSample VmfNdf::SampleVisibleNormal(const Vec3& v, const Vec2& u) const {
  // Rejection needs more than two random numbers: a stream seeded from u keeps the sampler a
  // deterministic function of u, as the interface promises.
  std::mt19937_64 rng(static_cast<uint64_t>(u.x() * 9007199254740992.0) ^
                      (static_cast<uint64_t>(u.y() * 9007199254740992.0) << 1));
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  for (int attempt = 0; attempt < 1000000; ++attempt) {
    const Vec3 h = SampleLobe(uniform(rng), uniform(rng));
    if (h.z() <= 0) continue;
    if (uniform(rng) < std::max(0.0, v.dot(h))) {
      const double pdf = VisibleNormalPdf(v, h);
      return {h, pdf, std::min(1.0, ProjectedArea(v) / v.z())};
    }
  }
  throw common::Error(common::ErrorKind::kNumerical, "vmf NDF", "visible-normal sampling did not accept a sample");
}

}  // namespace svbtdf::model
