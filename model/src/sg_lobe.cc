#include "svbtdf/model/sg_lobe.h"

#include <Eigen/Dense>
#include <cmath>

#include "svbtdf/common/error.h"

namespace svbtdf::model {
namespace {

// Parameters: axis as (theta, phi), ln lambda, ln a: unconstrained, and the axis stays unit.
using Params = Eigen::Vector4d;

SphericalGaussian LobeOf(const Params& p) {
  return {SphericalDirection(p[0], p[1]), std::exp(p[2]), std::exp(p[3])};
}

double WeightedError(const Params& p, const std::vector<Vec3>& d, const std::vector<double>& f,
                     const std::vector<double>& w) {
  const SphericalGaussian g = LobeOf(p);
  double error = 0;
  for (size_t k = 0; k < d.size(); ++k) error += w[k] * Square(g(d[k]) - f[k]);
  return error;
}

}  // namespace

SphericalGaussianFit FitSphericalGaussian(const std::vector<Vec3>& directions, const std::vector<double>& values,
                                          const std::vector<double>& weights) {
  const size_t n = directions.size();
  if (values.size() != n || weights.size() != n || n < 4) {
    common::ThrowInvalidInput("spherical Gaussian fit", "needs at least 4 samples with one value and one weight each");
  }
  // Moments: the value-weighted mean direction gives the axis; its length R the sharpness
  // (Banerjee et al.'s approximation for a vMF lobe, lambda ~ R (3 - R^2) / (1 - R^2)).
  Vec3 mean = Vec3::Zero();
  double mass = 0, norm = 0;
  for (size_t k = 0; k < n; ++k) {
    mean += weights[k] * values[k] * directions[k];
    mass += weights[k] * values[k];
    norm += weights[k] * Square(values[k]);
  }
  if (!(mass > 0)) common::ThrowInvalidInput("spherical Gaussian fit", "the slice has no positive value");
  const double r = std::min(mean.norm() / mass, 0.999);
  const Vec3 axis = mean.normalized();
  Params p;
  p << std::acos(std::clamp(axis.z(), -1.0, 1.0)), std::atan2(axis.y(), axis.x()),
      std::log(std::max(1e-3, r * (3 - r * r) / (1 - r * r))), 0.0;
  // Amplitude by linear least squares for the initial shape.
  {
    const SphericalGaussian g = LobeOf(p);
    double num = 0, den = 0;
    for (size_t k = 0; k < n; ++k) {
      const double shape = g(directions[k]) / g.amplitude;
      num += weights[k] * shape * values[k];
      den += weights[k] * shape * shape;
    }
    p[3] = std::log(std::max(num / den, 1e-300));
  }
  // Levenberg-Marquardt with a forward-difference Jacobian.
  SphericalGaussianFit fit;
  double lambda_lm = 1e-3;
  double error = WeightedError(p, directions, values, weights);
  for (fit.iterations = 0; fit.iterations < 100; ++fit.iterations) {
    Eigen::MatrixXd jacobian(n, 4);
    Eigen::VectorXd residual(n);
    const SphericalGaussian g = LobeOf(p);
    for (size_t k = 0; k < n; ++k) residual[k] = std::sqrt(weights[k]) * (g(directions[k]) - values[k]);
    for (int j = 0; j < 4; ++j) {
      Params q = p;
      const double step = 1e-6 * std::max(1.0, std::abs(p[j]));
      q[j] += step;
      const SphericalGaussian gq = LobeOf(q);
      for (size_t k = 0; k < n; ++k) {
        jacobian(k, j) = (std::sqrt(weights[k]) * (gq(directions[k]) - values[k]) - residual[k]) / step;
      }
    }
    const Eigen::Matrix4d jtj = jacobian.transpose() * jacobian;
    const Eigen::Vector4d jtr = jacobian.transpose() * residual;
    bool improved = false;
    while (lambda_lm < 1e12) {
      Eigen::Matrix4d damped = jtj;
      damped.diagonal() *= 1.0 + lambda_lm;
      const Params candidate = p - damped.ldlt().solve(jtr);
      const double candidate_error = WeightedError(candidate, directions, values, weights);
      if (std::isfinite(candidate_error) && candidate_error < error) {
        improved = error - candidate_error > 1e-14 * error;
        p = candidate;
        error = candidate_error;
        lambda_lm = std::max(1e-9, lambda_lm * 0.3);
        break;
      }
      lambda_lm *= 10;
    }
    if (!improved) break;
  }
  fit.lobe = LobeOf(p);
  fit.relative_l2 = norm > 0 ? std::sqrt(error / norm) : 0.0;
  return fit;
}

}  // namespace svbtdf::model
