#pragma once
// Levenberg-Marquardt for small dense least-squares problems in a box: a handful of parameters,
// a few hundred residuals, solved once per texel (the refinement's weights, 360,000 times at
// paper scale). Ceres solved them at the same steps but spent more time in its general machinery
// (program evaluation, array checks, a projected line search) than in the cost function itself:
// 45% of the refinement, the cost a third of that (docs/benchmarks.md, bench_refine). Here the
// problem hands over its normal equations directly and the step is Ceres' own: the damped system
// (J^T J + diag(J^T J) / mu) delta = -J^T r, with Ceres' radius update and stopping rules, the
// step projected onto the box.

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

namespace svbtdf::common {

struct BoxLevenbergMarquardtOptions {
  int max_iterations = 25;
  // Ceres' defaults (ceres::Solver::Options), so that the fits stop where they stopped before.
  double function_tolerance = 1e-6;   // relative change of the cost
  double gradient_tolerance = 1e-10;  // largest component of the projected gradient
  double parameter_tolerance = 1e-8;  // step length relative to |x|
  double initial_radius = 1e4;        // mu: the damping is diag(J^T J) / mu
  double max_radius = 1e16;
  double min_radius = 1e-32;
  double min_relative_decrease = 1e-3;  // a step is taken when it gains this share of the model's decrease
};

struct BoxLevenbergMarquardtSummary {
  bool usable = false;  // the cost was finite at the start (x is then never worse than there)
  bool converged = false;
  int iterations = 0;
  int evaluations = 0;
  double initial_cost = 0, final_cost = 0;
};

// Whether the bound at which a parameter sits holds it against the descent (gradient g).
inline bool HeldByBound(double x, double g, double lower, double upper) {
  return (x <= lower && g > 0) || (x >= upper && g < 0);
}

// The problem's interface (a template parameter, to keep the calls inlined):
//   double Cost(const Eigen::VectorXd& x) const;  // 1/2 |r(x)|^2, or a non-finite value
//   double Linearize(const Eigen::VectorXd& x, Eigen::MatrixXd* jtj, Eigen::VectorXd* jtr) const;
//       // the same cost, with J^T J and J^T r at x
// Minimises the cost over lower <= x <= upper from x (moved into the box first).
template <typename Problem>
BoxLevenbergMarquardtSummary MinimizeInBox(const Problem& problem, const Eigen::VectorXd& lower,
                                           const Eigen::VectorXd& upper, Eigen::VectorXd* x,
                                           const BoxLevenbergMarquardtOptions& options = {}) {
  BoxLevenbergMarquardtSummary summary;
  const auto project = [&](const Eigen::VectorXd& v) -> Eigen::VectorXd { return v.cwiseMax(lower).cwiseMin(upper); };
  *x = project(*x);
  const Eigen::Index p = x->size();
  Eigen::MatrixXd jtj(p, p);
  Eigen::VectorXd jtr(p);
  double cost = problem.Linearize(*x, &jtj, &jtr);
  ++summary.evaluations;
  summary.initial_cost = summary.final_cost = cost;
  if (!std::isfinite(cost) || !jtj.allFinite() || !jtr.allFinite()) return summary;
  summary.usable = true;

  double radius = options.initial_radius, decrease_factor = 2.0;
  // A step refused: damp harder, twice as fast each time in a row (Ceres' rule).
  const auto shrink = [&] {
    radius /= decrease_factor;
    decrease_factor *= 2.0;
  };
  // The projected gradient: zero in a component where the box stops the descent.
  const auto converged_by_gradient = [&] {
    return (*x - project(*x - jtr)).cwiseAbs().maxCoeff() <= options.gradient_tolerance;
  };
  if (converged_by_gradient()) {
    summary.converged = true;
    return summary;
  }
  while (summary.iterations < options.max_iterations && radius > options.min_radius) {
    ++summary.iterations;
    // Ceres' LM diagonal: diag(J^T J), clamped away from 0 so that a dead parameter stays damped.
    Eigen::MatrixXd damped = jtj;
    damped.diagonal() += jtj.diagonal().cwiseMax(1e-6).cwiseMin(1e32) / radius;
    // A parameter on a bound that the gradient pushes outward stays there, and the step is solved
    // for the others alone (projected Newton): solving for all and projecting afterwards would
    // aim the free ones at a point the bound one cannot reach, and stall against the bound.
    Eigen::VectorXd rhs = -jtr;
    for (Eigen::Index i = 0; i < p; ++i) {
      if (!HeldByBound((*x)[i], jtr[i], lower[i], upper[i])) continue;
      damped.row(i).setZero();
      damped.col(i).setZero();
      damped(i, i) = 1.0;
      rhs[i] = 0.0;
    }
    const Eigen::VectorXd delta = damped.ldlt().solve(rhs);
    const Eigen::VectorXd candidate = project(*x + delta);
    const Eigen::VectorXd step = candidate - *x;
    // The decrease the linearisation predicts for the step actually taken (after the box).
    const double model_decrease = -(jtr.dot(step) + 0.5 * step.dot(jtj * step));
    if (!delta.allFinite() || !(model_decrease > 0)) {
      shrink();
      continue;
    }
    if (step.norm() <= options.parameter_tolerance * (x->norm() + options.parameter_tolerance)) {
      summary.converged = true;
      break;
    }
    const double candidate_cost = problem.Cost(candidate);
    ++summary.evaluations;
    const double relative_decrease = (cost - candidate_cost) / model_decrease;
    if (!std::isfinite(candidate_cost) || !(relative_decrease > options.min_relative_decrease)) {
      shrink();
      continue;
    }
    // Taken: grow the radius by how well the model predicted (Nielsen's rule, as Ceres).
    const double cost_change = cost - candidate_cost;
    radius = std::min(options.max_radius, radius / std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * relative_decrease - 1.0, 3)));
    decrease_factor = 2.0;
    *x = candidate;
    cost = problem.Linearize(*x, &jtj, &jtr);
    ++summary.evaluations;
    summary.final_cost = cost;
    if (cost_change <= options.function_tolerance * (cost + cost_change) || converged_by_gradient()) {
      summary.converged = true;
      break;
    }
  }
  return summary;
}

// Non-negative least squares over a few columns, from their normal equations N = A^T W A and
// b = A^T W y: at most kMaxNonNegativeColumns columns, held in matrices that stay off the heap
// (the slab fit solves one at every residual evaluation).
constexpr int kMaxNonNegativeColumns = 4;
using NonNegativeMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxNonNegativeColumns, kMaxNonNegativeColumns>;
using NonNegativeVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxNonNegativeColumns, 1>;

// The amounts x >= 0 of least cost y^T W y - x^T b. With so few columns the active set is found by
// trying every subset of them: each subset's unconstrained solution, the feasible one that lowers
// the cost most (the exact answer: the constrained optimum is the unconstrained optimum of its
// own support). Subsets must hold every column of `required` (a bitmask); a subset whose columns
// are (nearly) linearly dependent is skipped (its shapes are the others'). All zero when no subset
// is feasible.
inline NonNegativeVector NonNegativeLeastSquares(const NonNegativeMatrix& normal, const NonNegativeVector& right,
                                                 unsigned required = 0) {
  const int n = static_cast<int>(right.size());
  NonNegativeVector best = NonNegativeVector::Zero(n);
  double best_gain = 0.0;  // x^T b: how far the subset's solution lowers the cost
  int in[kMaxNonNegativeColumns];
  for (unsigned subset = 1; subset < (1u << n); ++subset) {
    if ((subset & required) != required) continue;
    int m = 0;
    for (int c = 0; c < n; ++c) {
      if (subset & (1u << c)) in[m++] = c;
    }
    NonNegativeMatrix sub(m, m);
    NonNegativeVector sub_right(m);
    for (int a = 0; a < m; ++a) {
      sub_right[a] = right[in[a]];
      for (int b = 0; b < m; ++b) sub(a, b) = normal(in[a], in[b]);
    }
    if (!(sub.determinant() > 1e-12 * sub.diagonal().prod())) continue;
    const NonNegativeVector amounts = sub.ldlt().solve(sub_right);
    if (!amounts.allFinite() || (amounts.array() < 0).any()) continue;
    const double gain = amounts.dot(sub_right);
    if (gain > best_gain) {
      best_gain = gain;
      best.setZero();
      for (int a = 0; a < m; ++a) best[in[a]] = amounts[a];
    }
  }
  return best;
}

}  // namespace svbtdf::common
