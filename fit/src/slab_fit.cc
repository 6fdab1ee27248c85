#include "svbtdf/fit/slab_fit.h"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "svbtdf/common/error.h"
#include "svbtdf/model/dual_microfacet.h"
#include "svbtdf/model/ggx.h"
#include "svbtdf/model/slab_transmission.h"
#include "small_problem.h"

namespace svbtdf::fit {
namespace {

// Parameters: ln entry roughness, ln exit roughness. The scale k and the internal reflection's
// amount are linear: for any pair of roughnesses their best values are found in closed form
// (variable projection), so the optimiser searches two dimensions only.
constexpr int kNumParameters = 2;
// GGX alphas the fit may take: narrower than 0.01 no dot spacing resolves, wider than 1.5 is
// flatter than a Lambertian sheet's lobe.
const double kLowerLnRoughness = std::log(0.01), kUpperLnRoughness = std::log(1.5);

double Weight(const TexelSlice& slice, int k) { return slice.weight.empty() ? 1.0 : slice.weight[k]; }

// rho_TT of every row at unit scale, for one pair of roughnesses.
void RowShapes(const SlabInterfaces& slab, double eta, const TexelSlice& slice, const std::vector<int>& rows,
               std::vector<double>* shapes) {
  const model::GgxNdf entry(slab.entry_roughness), exit(slab.exit_roughness);
  const model::SlabTransmission transmission(entry, exit, eta);
  const model::SlabTransmission::ForViewer viewer = transmission.Viewer(slice.view);
  shapes->resize(rows.size());
  for (size_t j = 0; j < rows.size(); ++j) (*shapes)[j] = viewer.Rho(slice.light[rows[j]]);
}

// The internal reflection's shape at every row, for one pair of roughnesses.
std::vector<double> RowInternalReflection(const SlabInterfaces& slab, double eta, const TexelSlice& slice,
                                          const std::vector<int>& rows) {
  const model::GgxNdf entry(slab.entry_roughness), exit(slab.exit_roughness);
  const model::SlabInternalReflection paths(entry, exit, eta);
  std::vector<double> values(rows.size());
  for (size_t j = 0; j < rows.size(); ++j) values[j] = paths.Rho(slice.light[rows[j]], slice.view);
  return values;
}

// The model of the rows: k (shape + h halo), its two linear amounts a = k and b = k h >= 0.
struct LinearAmounts {
  double direct = 0, internal = 0;
  double At(const std::vector<double>& shapes, const std::vector<double>* halo, size_t j) const {
    return direct * shapes[j] + (halo ? internal * (*halo)[j] : 0.0);
  }
};

// The least-squares amounts of `shapes` (and `halo`, when given) against the rows' rho, both >= 0.
LinearAmounts BestAmounts(const TexelSlice& slice, const std::vector<int>& rows, const std::vector<double>& shapes,
                          const std::vector<double>* halo) {
  Eigen::Matrix2d normal = Eigen::Matrix2d::Zero();
  Eigen::Vector2d right = Eigen::Vector2d::Zero();
  for (size_t j = 0; j < rows.size(); ++j) {
    const double w = Weight(slice, rows[j]), rho = slice.rho[rows[j]];
    const Eigen::Vector2d column(shapes[j], halo ? (*halo)[j] : 0.0);
    normal += w * column * column.transpose();
    right += w * rho * column;
  }
  LinearAmounts amounts;
  if (halo && normal.determinant() > 1e-12 * normal(0, 0) * normal(1, 1)) {
    const Eigen::Vector2d both = normal.ldlt().solve(right);
    if (both[0] >= 0 && both[1] >= 0) return {both[0], both[1]};
  }
  // The halo alone (a negative amount of the direct light means no lobe) or the direct light alone.
  amounts.direct = normal(0, 0) > 0 ? std::max(0.0, right[0] / normal(0, 0)) : 0.0;
  return amounts;
}

// The residuals are differences of rho relative to the slice's brightest sample, not of its
// logarithm (as the dual-microfacet fit's linear ln D system needs). The slab's parameters shape
// the whole lobe, so the fit should weigh the samples by what they hold: in log residuals the
// dim far tails, where a real slab sends the broad halo of light reflected inside it (which the
// model lacks, docs/model.md), pulled the exit's roughness of the Monte Carlo truth from 0.18
// to 0.55 and left the lobe's peak 60% short. It is also what `svbtdf compare` measures.
//
// `halo`: the internal reflection's shape at every row, held fixed while the roughnesses move
// (it is recomputed between passes), or null.
struct SlabResidual {
  const TexelSlice* slice;
  const std::vector<int>* rows;
  double eta;
  double brightest;
  const std::vector<double>* halo;

  bool operator()(double const* const* parameters, double* residuals) const {
    const double* p = parameters[0];
    std::vector<double> shapes;
    RowShapes({std::exp(p[0]), std::exp(p[1])}, eta, *slice, *rows, &shapes);
    const LinearAmounts amounts = BestAmounts(*slice, *rows, shapes, halo);
    for (size_t j = 0; j < rows->size(); ++j) {
      const int row = (*rows)[j];
      residuals[j] = std::sqrt(Weight(*slice, row)) * (amounts.At(shapes, halo, j) - slice->rho[row]) / brightest;
    }
    return true;
  }
};

double Cost(const TexelSlice& slice, const std::vector<int>& rows, const std::vector<double>& shapes) {
  const LinearAmounts amounts = BestAmounts(slice, rows, shapes, nullptr);
  double cost = 0;
  for (size_t j = 0; j < rows.size(); ++j) {
    cost += Weight(slice, rows[j]) * model::Square(amounts.At(shapes, nullptr, j) - slice.rho[rows[j]]);
  }
  return cost;
}

// The least-cost start on a coarse grid of roughness pairs: the cost has a long valley along
// which one side's roughness trades for the other's, and LM started on the wrong side of a
// shallow ridge stays there.
std::array<double, kNumParameters> CoarseStart(const TexelSlice& slice, const std::vector<int>& rows, double eta) {
  std::array<double, kNumParameters> best = {std::log(0.2), std::log(0.2)};
  double best_cost = std::numeric_limits<double>::infinity();
  std::vector<double> shapes;
  for (double entry : {0.03, 0.07, 0.15, 0.3, 0.6}) {
    for (double exit : {0.03, 0.07, 0.15, 0.3, 0.6}) {
      RowShapes({entry, exit}, eta, slice, rows, &shapes);
      const double cost = Cost(slice, rows, shapes);
      if (cost < best_cost) best_cost = cost, best = {std::log(entry), std::log(exit)};
    }
  }
  return best;
}

// Per-channel scales by linear least squares against the fitted shape (as the dual fit does).
std::array<double, 3> ChannelScales(double k_s, const TexelSlice& slice, const std::vector<int>& rows,
                                    const std::vector<double>& shapes) {
  if (slice.rho_rgb.size() != slice.rho.size()) return {k_s, k_s, k_s};
  std::array<double, 3> model_data = {0, 0, 0};
  double model_model = 0;
  for (size_t j = 0; j < rows.size(); ++j) {
    const double w = Weight(slice, rows[j]);
    model_model += w * shapes[j] * shapes[j];
    for (int c = 0; c < 3; ++c) model_data[c] += w * shapes[j] * slice.rho_rgb[rows[j]][c];
  }
  if (!(model_model > 0)) return {k_s, k_s, k_s};
  return {model_data[0] / model_model, model_data[1] / model_model, model_data[2] / model_model};
}

// Standard errors of the two roughnesses and their correlation from the Jacobian J of the
// projected residuals r at the solution (Golub and Pereyra: the scale's own uncertainty is
// eliminated, not ignored), by the sandwich (J^T J)^-1 (sum_k r_k^2 J_k^T J_k) (J^T J)^-1 of
// ln r: the residuals are not equally noisy (a camera's noise grows with the signal), which
// s^2 (J^T J)^-1 would assume. Then se(r) = r se(ln r).
void MeasureUncertainty(ceres::Problem* problem, int num_rows, int num_linear, SlabFitResult* result) {
  double cost = 0;
  std::vector<double> residuals;
  ceres::CRSMatrix crs;
  if (!problem->Evaluate(ceres::Problem::EvaluateOptions(), &cost, &residuals, nullptr, &crs)) return;
  Eigen::MatrixXd jacobian = Eigen::MatrixXd::Zero(crs.num_rows, crs.num_cols);
  for (int r = 0; r < crs.num_rows; ++r) {
    for (int k = crs.rows[r]; k < crs.rows[r + 1]; ++k) jacobian(r, crs.cols[k]) = crs.values[k];
  }
  const Eigen::Matrix2d normal = jacobian.transpose() * jacobian;
  const int dof = num_rows - kNumParameters - num_linear;  // the linear amounts are parameters too
  if (dof <= 0 || !(normal.determinant() > 0)) return;
  Eigen::Matrix2d meat = Eigen::Matrix2d::Zero();
  for (int r = 0; r < crs.num_rows; ++r) {
    const Eigen::Vector2d row = jacobian.row(r).transpose();
    meat += model::Square(residuals[r]) * row * row.transpose();
  }
  const Eigen::Matrix2d bread = normal.inverse();
  // The small-sample correction n / dof of the sandwich (HC1).
  const Eigen::Matrix2d covariance = (static_cast<double>(num_rows) / dof) * bread * meat * bread;
  if (!(covariance(0, 0) >= 0) || !(covariance(1, 1) >= 0)) return;
  result->entry_roughness_se = result->interfaces.entry_roughness * std::sqrt(covariance(0, 0));
  result->exit_roughness_se = result->interfaces.exit_roughness * std::sqrt(covariance(1, 1));
  const double scale = std::sqrt(covariance(0, 0) * covariance(1, 1));
  result->roughness_correlation = scale > 0 ? covariance(0, 1) / scale : 0.0;
}

}  // namespace

double SlabShape(const SlabInterfaces& slab, double eta, const model::Vec3& i, const model::Vec3& o) {
  const model::GgxNdf entry(slab.entry_roughness), exit(slab.exit_roughness);
  double rho = model::SlabTransmission(entry, exit, eta).Rho(i, o);
  if (slab.internal_reflection > 0) rho += slab.internal_reflection * model::SlabInternalReflection(entry, exit, eta).Rho(i, o);
  return rho;
}

SlabFitter::SlabFitter(double eta, SlabFitOptions options) : eta_(eta), options_(options) {
  model::DualMicrofacetModel validate_eta(eta);
}

double SlabFitter::Rho(const SlabFitResult& fit, const model::Vec3& i, const model::Vec3& o) const {
  return fit.k_s * SlabShape(fit.interfaces, eta_, i, o);
}

namespace {

// Levenberg-Marquardt over the two roughnesses from `p`, the halo's shape held fixed (or none).
ceres::Solver::Summary SolveRoughnesses(const TexelSlice& slice, const std::vector<int>& rows, double eta, double brightest,
                                        const std::vector<double>* halo, std::array<double, kNumParameters>* p,
                                        ceres::Problem* problem) {
  auto* cost = new ceres::DynamicNumericDiffCostFunction<SlabResidual, ceres::CENTRAL>(
      new SlabResidual{&slice, &rows, eta, brightest, halo});
  cost->AddParameterBlock(kNumParameters);
  cost->SetNumResiduals(static_cast<int>(rows.size()));
  problem->AddResidualBlock(cost, nullptr, p->data());
  for (int side = 0; side < kNumParameters; ++side) {
    problem->SetParameterLowerBound(p->data(), side, kLowerLnRoughness);
    problem->SetParameterUpperBound(p->data(), side, kUpperLnRoughness);
  }
  ceres::Solver::Summary summary;
  ceres::Solve(SmallProblemOptions(50), problem, &summary);
  return summary;
}

}  // namespace

SlabFitResult SlabFitter::Fit(const TexelSlice& slice) const {
  if (slice.rho.size() != slice.light.size()) common::ThrowInvalidInput("texel slice", "rho and light sizes differ");
  double brightest = 0;
  for (size_t k = 0; k < slice.rho.size(); ++k) {
    if (Weight(slice, static_cast<int>(k)) > 0) brightest = std::max(brightest, slice.rho[k]);
  }
  // Every weighted sample is a row (a dark one says where the lobe is not); the count of bright
  // ones decides whether there is a lobe to fit at all.
  std::vector<int> rows;
  size_t bright = 0;
  for (size_t k = 0; k < slice.rho.size(); ++k) {
    if (!(Weight(slice, static_cast<int>(k)) > 0) || !std::isfinite(slice.rho[k])) continue;
    rows.push_back(static_cast<int>(k));
    if (slice.rho[k] > 0 && slice.rho[k] >= options_.dark_fraction * brightest) ++bright;
  }
  if (bright < 8 || !(brightest > 0)) {
    throw common::Error(common::ErrorKind::kNumerical, "texel slice", "too few bright samples for the slab fit");
  }
  std::array<double, kNumParameters> p = CoarseStart(slice, rows, eta_);
  // The direct light first; then, with the internal reflection's shape at the last roughnesses,
  // again (a fixed point: the shape moves little with them).
  auto problem = std::make_unique<ceres::Problem>();
  ceres::Solver::Summary summary = SolveRoughnesses(slice, rows, eta_, brightest, nullptr, &p, problem.get());
  std::vector<double> halo;
  const int passes = options_.internal_reflection ? options_.internal_reflection_passes : 0;
  for (int pass = 0; pass < passes; ++pass) {
    halo = RowInternalReflection({std::exp(p[0]), std::exp(p[1])}, eta_, slice, rows);
    problem = std::make_unique<ceres::Problem>();
    summary = SolveRoughnesses(slice, rows, eta_, brightest, &halo, &p, problem.get());
  }
  const std::vector<double>* fitted_halo = passes > 0 ? &halo : nullptr;

  SlabFitResult result;
  result.interfaces = {std::exp(p[0]), std::exp(p[1])};
  result.converged = summary.IsSolutionUsable();
  MeasureUncertainty(problem.get(), static_cast<int>(rows.size()), fitted_halo ? 2 : 1, &result);

  std::vector<double> shapes;
  RowShapes(result.interfaces, eta_, slice, rows, &shapes);
  const LinearAmounts amounts = BestAmounts(slice, rows, shapes, fitted_halo);
  result.k_s = amounts.direct;
  result.interfaces.internal_reflection = amounts.direct > 0 ? amounts.internal / amounts.direct : 0.0;
  // The shape the material will evaluate, with the halo at its weight.
  std::vector<double> model_shapes = shapes;
  if (fitted_halo) {
    for (size_t j = 0; j < rows.size(); ++j) model_shapes[j] += result.interfaces.internal_reflection * halo[j];
  }
  double squared_error = 0, squared_rho = 0, squared_log = 0;
  size_t logged = 0;
  for (size_t j = 0; j < rows.size(); ++j) {
    const double rho = slice.rho[rows[j]], predicted = result.k_s * model_shapes[j];
    squared_error += model::Square(predicted - rho);
    squared_rho += model::Square(rho);
    if (rho >= options_.dark_fraction * brightest && rho > 0 && predicted > 0) {
      squared_log += model::Square(std::log(predicted / rho)), ++logged;
    }
  }
  result.relative_rmse = squared_rho > 0 ? std::sqrt(squared_error / squared_rho) : 0.0;
  result.log_rms = logged > 0 ? std::sqrt(squared_log / logged) : 0.0;
  result.k_s_rgb = ChannelScales(result.k_s, slice, rows, model_shapes);
  return result;
}

}  // namespace svbtdf::fit
