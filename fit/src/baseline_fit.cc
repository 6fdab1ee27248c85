#include "svbtdf/fit/baseline_fit.h"

#include <ceres/ceres.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "svbtdf/common/error.h"
#include "svbtdf/model/dual_microfacet.h"
#include "svbtdf/model/ggx.h"
#include "small_problem.h"

namespace svbtdf::fit {
namespace {

// Parameters: ln alpha_x, ln alpha_y, azimuth, ln k.
double BaselineRho(const double* p, double eta, const model::Vec3& i, const model::Vec3& o) {
  return std::exp(p[3]) * BaselineShape({std::exp(p[0]), std::exp(p[1]), p[2]}, eta, i, o);
}

// Per-channel scales by linear least squares against the fitted shape (as the dual fit does).
std::array<double, 3> ChannelScales(const BaselineFitResult& fit, double eta, const TexelSlice& slice,
                                    const std::vector<int>& rows) {
  if (slice.rho_rgb.size() != slice.rho.size()) return {fit.k_s, fit.k_s, fit.k_s};
  std::array<double, 3> model_data = {0, 0, 0};
  double model_model = 0;
  for (int k : rows) {
    const double shape = BaselineShape(fit.lobe(), eta, slice.light[k], slice.view);
    model_model += shape * shape;
    for (int c = 0; c < 3; ++c) model_data[c] += shape * slice.rho_rgb[k][c];
  }
  if (!(model_model > 0)) return {fit.k_s, fit.k_s, fit.k_s};
  return {model_data[0] / model_model, model_data[1] / model_model, model_data[2] / model_model};
}

struct BaselineResidual {
  const TexelSlice* slice;
  const std::vector<int>* rows;
  double eta;

  bool operator()(double const* const* parameters, double* residuals) const {
    for (size_t j = 0; j < rows->size(); ++j) {
      const int k = (*rows)[j];
      const double rho = BaselineRho(parameters[0], eta, slice->light[k], slice->view);
      // A direction the single refraction cannot reach costs as much as a 1000x miss, so the
      // optimiser is pulled toward covering every bright sample.
      const double predicted = rho > 0 ? rho : 1e-3 * slice->rho[k];
      const double weight = slice->weight.empty() ? 1.0 : slice->weight[k];
      residuals[j] = std::sqrt(weight) * (std::log(predicted) - std::log(slice->rho[k]));
    }
    return true;
  }
};

}  // namespace

double BaselineShape(const BaselineLobe& lobe, double eta, const model::Vec3& i, const model::Vec3& o) {
  const model::GgxNdf ndf(lobe.alpha_x, lobe.alpha_y);
  const Eigen::AngleAxisd unrotate(-lobe.azimuth, model::Vec3::UnitZ());
  return model::WalterBtdf(ndf, unrotate * i, unrotate * o, 1.0, eta);
}

std::vector<double> BaselineLnD(const model::Hemicube& grid, const BaselineLobe& lobe) {
  const model::GgxNdf ndf(lobe.alpha_x, lobe.alpha_y);
  const Eigen::AngleAxisd unrotate(-lobe.azimuth, model::Vec3::UnitZ());
  std::vector<double> ln_d(grid.num_cells());
  for (int c = 0; c < grid.num_cells(); ++c) {
    ln_d[c] = std::log(std::max(ndf.D(unrotate * grid.CellCenter(c)), 1e-300));
  }
  return ln_d;
}

BaselineLobe BlendBaselineLobes(const std::vector<std::pair<BaselineLobe, double>>& weighted) {
  Eigen::Matrix2d moments = Eigen::Matrix2d::Zero();
  for (const auto& [lobe, weight] : weighted) {
    const Eigen::Rotation2Dd rotation(lobe.azimuth);
    const Eigen::Vector2d scales(model::Square(lobe.alpha_x), model::Square(lobe.alpha_y));
    moments += weight * (rotation.toRotationMatrix() * scales.asDiagonal() * rotation.toRotationMatrix().transpose());
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(moments);
  // Negative affine weights can undershoot: keep the lobe at least as narrow as the fit's bound.
  const double floor = model::Square(1e-3);
  const Eigen::Vector2d axis = eigen.eigenvectors().col(1);  // the larger eigenvalue: alpha_x
  BaselineLobe blended;
  blended.alpha_x = std::sqrt(std::max(eigen.eigenvalues()[1], floor));
  blended.alpha_y = std::sqrt(std::max(eigen.eigenvalues()[0], floor));
  blended.azimuth = std::remainder(std::atan2(axis.y(), axis.x()), model::kPi);
  return blended;
}

BaselineFitter::BaselineFitter(double eta, double dark_fraction) : eta_(eta), dark_fraction_(dark_fraction) {
  model::DualMicrofacetModel validate_eta(eta);
}

double BaselineFitter::Rho(const BaselineFitResult& fit, const model::Vec3& i, const model::Vec3& o) const {
  const double p[4] = {std::log(fit.alpha_x), std::log(fit.alpha_y), fit.azimuth, std::log(fit.k_s)};
  return BaselineRho(p, eta_, i, o);
}

BaselineFitResult BaselineFitter::Fit(const TexelSlice& slice) const {
  if (slice.rho.size() != slice.light.size()) common::ThrowInvalidInput("texel slice", "rho and light sizes differ");
  double brightest = 0;
  for (size_t k = 0; k < slice.rho.size(); ++k) {
    if (slice.weight.empty() || slice.weight[k] > 0) brightest = std::max(brightest, slice.rho[k]);
  }
  std::vector<int> rows;
  for (size_t k = 0; k < slice.rho.size(); ++k) {
    const bool weighted = slice.weight.empty() || slice.weight[k] > 0;
    if (weighted && slice.rho[k] > 0 && slice.rho[k] >= dark_fraction_ * brightest) rows.push_back(static_cast<int>(k));
  }
  if (rows.size() < 8) {
    throw common::Error(common::ErrorKind::kNumerical, "texel slice", "too few bright samples for the baseline fit");
  }
  // Start from a moderate isotropic lobe with the scale matching the brightest sample.
  double p[4] = {std::log(0.2), std::log(0.2), 0.0, 0.0};
  double sum_log_ratio = 0;
  int counted = 0;
  for (int k : rows) {
    const double predicted = BaselineRho(p, eta_, slice.light[k], slice.view);
    if (predicted > 0) sum_log_ratio += std::log(slice.rho[k] / predicted), ++counted;
  }
  if (counted > 0) p[3] = sum_log_ratio / counted;

  auto* cost = new ceres::DynamicNumericDiffCostFunction<BaselineResidual, ceres::CENTRAL>(
      new BaselineResidual{&slice, &rows, eta_});
  cost->AddParameterBlock(4);
  cost->SetNumResiduals(static_cast<int>(rows.size()));
  ceres::Problem problem;
  problem.AddResidualBlock(cost, nullptr, p);
  for (int axis = 0; axis < 2; ++axis) {
    problem.SetParameterLowerBound(p, axis, std::log(1e-3));
    problem.SetParameterUpperBound(p, axis, std::log(3.0));
  }
  const ceres::Solver::Options options = SmallProblemOptions(100);
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);

  BaselineFitResult result;
  result.alpha_x = std::exp(p[0]);
  result.alpha_y = std::exp(p[1]);
  result.azimuth = std::remainder(p[2], model::kPi);
  result.k_s = std::exp(p[3]);
  result.converged = summary.IsSolutionUsable();
  double squared_error = 0, squared_rho = 0, squared_log = 0;
  for (size_t k = 0; k < slice.rho.size(); ++k) {
    if (!(slice.weight.empty() || slice.weight[k] > 0)) continue;
    const double predicted = Rho(result, slice.light[k], slice.view);
    squared_error += model::Square(predicted - slice.rho[k]);
    squared_rho += model::Square(slice.rho[k]);
  }
  for (int k : rows) {
    const double predicted = Rho(result, slice.light[k], slice.view);
    if (predicted > 0) squared_log += model::Square(std::log(predicted / slice.rho[k]));
  }
  result.relative_rmse = squared_rho > 0 ? std::sqrt(squared_error / squared_rho) : 0.0;
  result.log_rms = std::sqrt(squared_log / rows.size());
  result.k_s_rgb = ChannelScales(result, eta_, slice, rows);
  return result;
}

}  // namespace svbtdf::fit
