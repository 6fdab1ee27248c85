#include "svbtdf/common/least_squares.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace svbtdf::common {
namespace {

// y_k = a exp(b t_k) + c at a few samples: nonlinear in b.
class ExponentialProblem {
 public:
  ExponentialProblem(const Eigen::VectorXd& truth, double noise, unsigned seed) : t_(Eigen::VectorXd::LinSpaced(40, 0, 2)) {
    std::mt19937 random(seed);
    std::normal_distribution<double> normal(0.0, noise);
    y_.resize(t_.size());
    for (Eigen::Index k = 0; k < t_.size(); ++k) y_[k] = Model(truth, t_[k]) + normal(random);
  }
  static double Model(const Eigen::VectorXd& x, double t) { return x[0] * std::exp(x[1] * t) + x[2]; }

  Eigen::VectorXd Residuals(const Eigen::VectorXd& x) const {
    Eigen::VectorXd r(t_.size());
    for (Eigen::Index k = 0; k < t_.size(); ++k) r[k] = Model(x, t_[k]) - y_[k];
    return r;
  }
  Eigen::MatrixXd Jacobian(const Eigen::VectorXd& x) const {
    Eigen::MatrixXd j(t_.size(), 3);
    for (Eigen::Index k = 0; k < t_.size(); ++k) {
      const double e = std::exp(x[1] * t_[k]);
      j.row(k) << e, x[0] * t_[k] * e, 1.0;
    }
    return j;
  }
  double Cost(const Eigen::VectorXd& x) const {
    ++evaluations;
    return 0.5 * Residuals(x).squaredNorm();
  }
  double Linearize(const Eigen::VectorXd& x, Eigen::MatrixXd* jtj, Eigen::VectorXd* jtr) const {
    ++evaluations;
    const Eigen::MatrixXd j = Jacobian(x);
    const Eigen::VectorXd r = Residuals(x);
    *jtj = j.transpose() * j;
    *jtr = j.transpose() * r;
    return 0.5 * r.squaredNorm();
  }
  mutable int evaluations = 0;

 private:
  Eigen::VectorXd t_, y_;
};

const double kInf = std::numeric_limits<double>::infinity();

TEST(MinimizeInBox, RecoversAnExponentialFromNoiselessSamples) {
  const Eigen::Vector3d truth(2.0, -1.3, 0.4);
  const ExponentialProblem problem(truth, 0.0, 1);
  Eigen::VectorXd x = Eigen::Vector3d(1.0, 0.0, 0.0);
  const Eigen::VectorXd lower = Eigen::Vector3d::Constant(-kInf), upper = Eigen::Vector3d::Constant(kInf);
  const BoxLevenbergMarquardtSummary summary = MinimizeInBox(problem, lower, upper, &x);
  ASSERT_TRUE(summary.usable);
  EXPECT_TRUE(summary.converged);
  EXPECT_NEAR(x[0], truth[0], 1e-6);
  EXPECT_NEAR(x[1], truth[1], 1e-6);
  EXPECT_NEAR(x[2], truth[2], 1e-6);
  EXPECT_LT(summary.final_cost, 1e-12);
  EXPECT_EQ(summary.evaluations, problem.evaluations);
}

// With noise the minimum is where the gradient vanishes: compare with a finite-difference
// gradient of the cost, which owes nothing to the solver's normal equations.
TEST(MinimizeInBox, EndsWhereTheCostsFiniteDifferenceGradientVanishes) {
  const ExponentialProblem problem(Eigen::Vector3d(1.5, 0.8, -0.2), 0.05, 7);
  Eigen::VectorXd x = Eigen::Vector3d(1.0, 0.0, 0.0);
  const Eigen::VectorXd lower = Eigen::Vector3d::Constant(-kInf), upper = Eigen::Vector3d::Constant(kInf);
  ASSERT_TRUE(MinimizeInBox(problem, lower, upper, &x).converged);
  const double cost = problem.Cost(x);
  for (int i = 0; i < 3; ++i) {
    const double h = 1e-5;
    Eigen::VectorXd plus = x, minus = x;
    plus[i] += h;
    minus[i] -= h;
    const double gradient = (problem.Cost(plus) - problem.Cost(minus)) / (2 * h);
    EXPECT_LT(std::abs(gradient), 1e-5 * std::max(1.0, cost)) << "parameter " << i;
  }
}

// A bound that binds: the minimum in the box has that parameter on its bound and the others at
// their best given it, which a fit of the others alone (the bound one fixed) finds too.
TEST(MinimizeInBox, StopsOnABoundThatBindsAndFitsTheRestGivenIt) {
  const ExponentialProblem problem(Eigen::Vector3d(2.0, -1.3, 0.4), 0.0, 3);
  Eigen::VectorXd lower = Eigen::Vector3d::Constant(-kInf), upper = Eigen::Vector3d::Constant(kInf);
  upper[2] = 0.1;  // c's truth (0.4) is outside
  // Both fits run to the gradient, not to the default relative change of the cost (1e-6),
  // which stops each within about 1e-6 of its optimum in a different place.
  BoxLevenbergMarquardtOptions options;
  options.function_tolerance = 0.0;
  options.max_iterations = 100;
  Eigen::VectorXd x = Eigen::Vector3d(1.0, 0.0, 0.0);
  const BoxLevenbergMarquardtSummary summary = MinimizeInBox(problem, lower, upper, &x, options);
  ASSERT_TRUE(summary.converged);
  EXPECT_DOUBLE_EQ(x[2], 0.1);

  Eigen::VectorXd fixed = Eigen::Vector3d(1.0, 0.0, 0.1);
  Eigen::VectorXd fixed_lower = lower, fixed_upper = upper;
  fixed_lower[2] = fixed_upper[2] = 0.1;
  ASSERT_TRUE(MinimizeInBox(problem, fixed_lower, fixed_upper, &fixed, options).converged);
  EXPECT_NEAR(x[0], fixed[0], 1e-8);
  EXPECT_NEAR(x[1], fixed[1], 1e-8);
  // The bound holds the cost up: moving c down (into the box) must not lower it.
  Eigen::VectorXd inside = x;
  inside[2] -= 1e-4;
  EXPECT_GT(problem.Cost(inside), problem.Cost(x));
}

TEST(MinimizeInBox, MovesAStartOutsideTheBoxIntoIt) {
  const ExponentialProblem problem(Eigen::Vector3d(2.0, -1.3, 0.4), 0.0, 3);
  const Eigen::VectorXd lower = Eigen::Vector3d(0.0, -5.0, -1.0), upper = Eigen::Vector3d(10.0, 5.0, 1.0);
  Eigen::VectorXd x = Eigen::Vector3d(20.0, -9.0, 3.0);
  ASSERT_TRUE(MinimizeInBox(problem, lower, upper, &x).usable);
  EXPECT_TRUE((x.array() >= lower.array()).all() && (x.array() <= upper.array()).all());
  EXPECT_NEAR(x[1], -1.3, 1e-6);
}

TEST(MinimizeInBox, ReportsANonFiniteStartAsUnusableAndLeavesItThere) {
  const ExponentialProblem problem(Eigen::Vector3d(2.0, -1.3, 0.4), 0.0, 3);
  const Eigen::VectorXd lower = Eigen::Vector3d::Constant(-kInf), upper = Eigen::Vector3d::Constant(kInf);
  Eigen::VectorXd x = Eigen::Vector3d(1.0, 1e6, 0.0);  // exp overflows
  const BoxLevenbergMarquardtSummary summary = MinimizeInBox(problem, lower, upper, &x);
  EXPECT_FALSE(summary.usable);
  EXPECT_EQ(summary.iterations, 0);
  EXPECT_EQ(x[1], 1e6);
}

TEST(MinimizeInBox, KeepsToItsIterationLimitAndNeverEndsAboveItsStart) {
  const ExponentialProblem problem(Eigen::Vector3d(2.0, -1.3, 0.4), 0.01, 5);
  const Eigen::VectorXd lower = Eigen::Vector3d::Constant(-kInf), upper = Eigen::Vector3d::Constant(kInf);
  Eigen::VectorXd x = Eigen::Vector3d(0.1, 3.0, -2.0);
  BoxLevenbergMarquardtOptions options;
  options.max_iterations = 2;
  const BoxLevenbergMarquardtSummary summary = MinimizeInBox(problem, lower, upper, &x, options);
  ASSERT_TRUE(summary.usable);
  EXPECT_LE(summary.iterations, 2);
  EXPECT_LE(summary.final_cost, summary.initial_cost);
  EXPECT_DOUBLE_EQ(summary.final_cost, problem.Cost(x));
}

// The amounts satisfy the optimality (Karush-Kuhn-Tucker) conditions of min |A x - y|^2 over
// x >= 0: the gradient N x - b is 0 where an amount is positive and >= 0 where it is 0. Random
// problems of 1-4 columns, with columns alike enough that the unconstrained solution often goes
// negative.
TEST(NonNegativeLeastSquares, MeetsTheOptimalityConditionsOfTheConstrainedProblem) {
  std::mt19937 random(5);
  std::normal_distribution<double> normal(0.0, 1.0);
  int constrained = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const int n = 1 + trial % kMaxNonNegativeColumns;
    Eigen::MatrixXd a(30, n);
    const Eigen::VectorXd common_column = Eigen::VectorXd::NullaryExpr(30, [&] { return std::abs(normal(random)); });
    for (int c = 0; c < n; ++c) {
      a.col(c) = common_column + 0.3 * Eigen::VectorXd::NullaryExpr(30, [&] { return normal(random); });
    }
    const Eigen::VectorXd y = a * Eigen::VectorXd::NullaryExpr(n, [&] { return normal(random); }) +
                              0.1 * Eigen::VectorXd::NullaryExpr(30, [&] { return normal(random); });
    const NonNegativeMatrix n_matrix = a.transpose() * a;
    const NonNegativeVector b = a.transpose() * y;
    const NonNegativeVector x = NonNegativeLeastSquares(n_matrix, b);
    const Eigen::VectorXd unconstrained = n_matrix.ldlt().solve(b);
    if ((unconstrained.array() < 0).any()) ++constrained;
    const NonNegativeVector gradient = n_matrix * x - b;
    const double scale = b.cwiseAbs().maxCoeff();
    for (int c = 0; c < n; ++c) {
      ASSERT_GE(x[c], 0.0) << trial;
      if (x[c] > 0) {
        EXPECT_NEAR(gradient[c], 0.0, 1e-9 * scale) << trial << ", column " << c;
      } else {
        EXPECT_GE(gradient[c], -1e-9 * scale) << trial << ", column " << c;
      }
    }
  }
  EXPECT_GT(constrained, 100);  // the bound was active often enough to test it
}

// A required column stays in the support even where leaving it out would cost less; a column the
// others already span is left out rather than solved for.
TEST(NonNegativeLeastSquares, KeepsTheRequiredColumnsAndSkipsDependentOnes) {
  NonNegativeMatrix normal(2, 2);
  normal << 1.0, 0.9, 0.9, 1.0;
  NonNegativeVector right(2);
  right << 0.5, 1.0;  // unconstrained: column 0 negative
  const NonNegativeVector free = NonNegativeLeastSquares(normal, right);
  EXPECT_EQ(free[0], 0.0);
  EXPECT_DOUBLE_EQ(free[1], 1.0);
  const NonNegativeVector with_first = NonNegativeLeastSquares(normal, right, /*required=*/1u);
  EXPECT_DOUBLE_EQ(with_first[0], 0.5);  // column 0 alone: the only feasible subset that holds it
  EXPECT_EQ(with_first[1], 0.0);
  NonNegativeMatrix twin(2, 2);
  twin << 1.0, 1.0, 1.0, 1.0;  // the same column twice
  NonNegativeVector twin_right(2);
  twin_right << 2.0, 2.0;
  const NonNegativeVector one = NonNegativeLeastSquares(twin, twin_right);
  EXPECT_DOUBLE_EQ(one[0] + one[1], 2.0);
  EXPECT_TRUE(one[0] == 0.0 || one[1] == 0.0);
}

}  // namespace
}  // namespace svbtdf::common
