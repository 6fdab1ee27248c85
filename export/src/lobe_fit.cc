#include "svbtdf/export/lobe_fit.h"

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "svbtdf/common/error.h"
#include "svbtdf/common/parallel.h"
#include "svbtdf/common/statistics.h"

namespace svbtdf::exporter {
namespace {

constexpr double kMassFraction = 0.01;  // cells with D h.z >= 1% of the peak (fit::NdfRelativeL2's)
// For a GGX lobe cut at D h.z >= 1% of its peak, E[slope_x^2] = c alpha_x^2 along each axis, with
// c = (ln 10 - 0.9) / 1.8 (the slope density is (1 + r^2)^-2, cut at r^2 = 9; small alpha).
constexpr double kTruncatedSlopeMoment = (2.302585092994046 - 0.9) / 1.8;
constexpr double kMinAlpha = 1e-3, kMaxAlpha = 4.0;
constexpr int kMaxIterations = 20;

// The parameters Levenberg-Marquardt moves: ln alpha_x, ln alpha_y, azimuth, ln scale.
using Params = Eigen::Vector4d;

double WrapAzimuth(double azimuth) {
  // A GGX lobe is symmetric under a half turn: keep the azimuth in [-pi/2, pi/2).
  const double pi = std::numbers::pi;
  azimuth = std::fmod(azimuth + pi / 2, pi);
  return (azimuth < 0 ? azimuth + pi : azimuth) - pi / 2;
}

// Cost (squared relative L2) of a lobe over the cells with mass, and its normal equations.
struct Evaluation {
  double cost = 0;
  Eigen::Matrix4d jtj = Eigen::Matrix4d::Zero();
  Eigen::Vector4d jtr = Eigen::Vector4d::Zero();
};

// A table's cells with mass, gathered so that every evaluation is a few vectorised passes.
struct MassCells {
  Eigen::ArrayXd x, y, z, target;  // cell centres; the table's D, normalised by its cell quadrature
  Eigen::ArrayXd weight;           // solid angle / sum of solid angle x target^2: the cost is relative

  Evaluation Evaluate(const Params& p) const {
    Evaluation e;
    const double ax = std::exp(p[0]), ay = std::exp(p[1]), scale = std::exp(p[3]);
    const double cos_a = std::cos(p[2]), sin_a = std::sin(p[2]);
    const double inv_ax2 = 1.0 / (ax * ax), inv_ay2 = 1.0 / (ay * ay);
    const Eigen::ArrayXd a = x * cos_a + y * sin_a, b = y * cos_a - x * sin_a;  // along and across the axis
    const Eigen::ArrayXd a2 = a.square() * inv_ax2, b2 = b.square() * inv_ay2;
    const Eigen::ArrayXd inv_u = (a2 + b2 + z.square()).inverse();
    const Eigen::ArrayXd model = scale / (std::numbers::pi * ax * ay) * inv_u.square();  // scale x GGX D
    const Eigen::ArrayXd residual = model - target;
    e.cost = (weight * residual.square()).sum();
    // d model / d(ln alpha_x, ln alpha_y, azimuth, ln scale)
    const std::array<Eigen::ArrayXd, 4> gradient = {model * (4.0 * a2 * inv_u - 1.0), model * (4.0 * b2 * inv_u - 1.0),
                                                    -4.0 * (inv_ax2 - inv_ay2) * model * a * b * inv_u, model};
    for (int i = 0; i < 4; ++i) {
      const Eigen::ArrayXd weighted_gradient = weight * gradient[i];
      e.jtr[i] = (weighted_gradient * residual).sum();
      for (int j = 0; j <= i; ++j) e.jtj(i, j) = e.jtj(j, i) = (weighted_gradient * gradient[j]).sum();
    }
    return e;
  }
};

// Levenberg-Marquardt from `p`; returns the steps taken and leaves the minimum in `p`, its cost in `cost`.
int Minimise(const MassCells& cells, Params& p, double& cost) {
  Evaluation current = cells.Evaluate(p);
  double damping = 1e-3;
  int iteration = 0;
  for (; iteration < kMaxIterations; ++iteration) {
    Eigen::Matrix4d system = current.jtj;
    // Marquardt's scaling, with a floor: the azimuth of a nearly isotropic lobe has no gradient.
    for (int k = 0; k < 4; ++k) system(k, k) += damping * std::max(current.jtj(k, k), 1e-9);
    Params candidate = p - system.ldlt().solve(current.jtr);
    candidate[0] = std::clamp(candidate[0], std::log(kMinAlpha), std::log(kMaxAlpha));
    candidate[1] = std::clamp(candidate[1], std::log(kMinAlpha), std::log(kMaxAlpha));
    const Evaluation next = cells.Evaluate(candidate);
    if (!(next.cost < current.cost)) {  // worse, or not a number: a shorter step
      damping *= 8;
      if (damping > 1e8) break;
      continue;
    }
    const double gain = current.cost - next.cost;
    p = candidate, current = next;
    damping = std::max(damping / 4, 1e-9);
    // Converged when the relative error moves by less than 0.01% of itself.
    if (gain < 2e-4 * current.cost + 1e-14) break;
  }
  cost = current.cost;
  return iteration;
}

// The slopes' second moments under D h.z, decomposed into the lobe's axes: close enough that a
// few Levenberg-Marquardt steps finish the fit.
GgxLobe MomentStart(const MassCells& cells) {
  const Eigen::ArrayXd mass = cells.target * cells.z * cells.weight;  // any constant factor divides out
  const Eigen::ArrayXd sx = cells.x / cells.z, sy = cells.y / cells.z;
  Eigen::Matrix2d moments;
  moments(0, 0) = (mass * sx * sx).sum();
  moments(1, 1) = (mass * sy * sy).sum();
  moments(0, 1) = moments(1, 0) = (mass * sx * sy).sum();
  moments /= std::max(mass.sum(), 1e-300);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> solver(moments);
  const auto alpha = [](double variance) {
    return std::clamp(std::sqrt(std::max(variance, 0.0) / kTruncatedSlopeMoment), kMinAlpha, kMaxAlpha);
  };
  const Eigen::Vector2d major = solver.eigenvectors().col(1);  // eigenvalues ascend
  return {alpha(solver.eigenvalues()(1)), alpha(solver.eigenvalues()(0)), WrapAzimuth(std::atan2(major.y(), major.x()))};
}

}  // namespace

GgxLobeFitter::GgxLobeFitter(const model::Hemicube& grid) {
  cells_.reserve(grid.num_cells());
  for (int c = 0; c < grid.num_cells(); ++c) {
    const model::Vec3 h = grid.CellCenter(c);
    cells_.push_back({h.x(), h.y(), h.z(), grid.CellSolidAngle(c)});
  }
}

// The cells where the table's D h.z is at least kMassFraction of its peak, D normalised by the
// table's own cell quadrature of D h.z (the lobe's fitted scale absorbs what that quadrature and
// the lobe's exact normalisation disagree on).
template <typename Cells>
MassCells GatherMassCells(const Cells& all, const std::vector<double>& cell_d) {
  double peak = 0, integral = 0;
  for (size_t c = 0; c < all.size(); ++c) {
    peak = std::max(peak, cell_d[c] * all[c].z);
    integral += cell_d[c] * all[c].z * all[c].solid_angle;
  }
  std::vector<int> mass;
  for (size_t c = 0; c < all.size(); ++c) {
    if (all[c].z > 0 && cell_d[c] * all[c].z >= kMassFraction * peak) mass.push_back(static_cast<int>(c));
  }
  const Eigen::Index n = static_cast<Eigen::Index>(mass.size());
  MassCells cells{Eigen::ArrayXd(n), Eigen::ArrayXd(n), Eigen::ArrayXd(n), Eigen::ArrayXd(n), Eigen::ArrayXd(n)};
  for (Eigen::Index k = 0; k < n; ++k) {
    const auto& cell = all[mass[k]];
    cells.x[k] = cell.x, cells.y[k] = cell.y, cells.z[k] = cell.z;
    cells.target[k] = cell_d[mass[k]] / integral, cells.weight[k] = cell.solid_angle;
  }
  cells.weight /= (cells.weight * cells.target.square()).sum();
  return cells;
}

LobeFit GgxLobeFitter::Fit(const std::vector<double>& cell_d) const {
  const MassCells cells = GatherMassCells(cells_, cell_d);
  const GgxLobe start = MomentStart(cells);
  Params p(std::log(start.alpha_x), std::log(start.alpha_y), start.azimuth, 0.0);
  double cost = 0;
  LobeFit fit;
  fit.iterations = Minimise(cells, p, cost);
  fit.relative_error = std::sqrt(cost);
  // The first axis is the longer one, as MomentStart chose it; keep that order if LM swapped them.
  double ax = std::exp(p[0]), ay = std::exp(p[1]), azimuth = p[2];
  if (ay > ax) std::swap(ax, ay), azimuth += std::numbers::pi / 2;
  fit.lobe = {ax, ay, WrapAzimuth(azimuth)};
  return fit;
}

void RequireLobeFittable(const fit::Material& material, const std::string& source) {
  if (material.model == fit::MaterialModel::kSlab) {
    // One lobe per texel would have to stand for the convolution of two interfaces; no fit of it
    // has been measured yet, so nothing is exported that would misstate the material.
    common::ThrowInvalidInput(source, "is a slab material (two rough interfaces); a GGX lobe per texel is fitted only to "
                              "a dual-microfacet material's NDF", "export the dual-microfacet fit of the same session "
                              "(svbtdf fit --model dual)");
  }
}

MaterialLobes FitMaterialLobes(const fit::Material& material, int threads, const std::string& source) {
  RequireLobeFittable(material, source);
  MaterialLobes lobes;
  const int width = material.width, height = material.height;
  lobes.alpha_x = common::FloatImage(width, height, 1);
  lobes.alpha_y = common::FloatImage(width, height, 1);
  lobes.azimuth = common::FloatImage(width, height, 1);
  lobes.relative_error = common::FloatImage(width, height, 1);
  if (material.model == fit::MaterialModel::kWalterGgx) {
    // The baseline's texels are GGX lobes already (docs/material-format.md).
    lobes.alpha_x = material.baseline_alpha_x, lobes.alpha_y = material.baseline_alpha_y;
    lobes.azimuth = material.baseline_azimuth, lobes.exact = true;
    return lobes;
  }
  const fit::MaterialEvaluator evaluator(material);
  const GgxLobeFitter fitter{model::Hemicube(material.ndf_resolution)};
  common::ParallelFor(static_cast<int64_t>(width) * height, threads, 256, [&](int64_t begin, int64_t end) {
    for (int64_t texel = begin; texel < end; ++texel) {
      const int x = static_cast<int>(texel % width), y = static_cast<int>(texel / width);
      const LobeFit fit = fitter.Fit(evaluator.TexelCellD(x, y));
      lobes.alpha_x.at(x, y) = static_cast<float>(fit.lobe.alpha_x);
      lobes.alpha_y.at(x, y) = static_cast<float>(fit.lobe.alpha_y);
      lobes.azimuth.at(x, y) = static_cast<float>(fit.lobe.azimuth);
      lobes.relative_error.at(x, y) = static_cast<float>(fit.relative_error);
    }
  });
  return lobes;
}

ErrorDistribution Distribution(const common::FloatImage& map) {
  const std::vector<double> values(map.pixels.begin(), map.pixels.end());
  return {common::Quantile(values, 0.5), common::Quantile(values, 0.9), common::Quantile(values, 1.0)};
}

}  // namespace svbtdf::exporter
