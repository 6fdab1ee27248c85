#pragma once
// The standard errors of the fit's least-squares systems (docs/fitting.md, "Uncertainty").

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

namespace svbtdf::fit {

// Covariance of the parameters of a least-squares fit from its Jacobian J (n residuals x p
// parameters) and its residuals r at the optimum: the sandwich (HC1)
//   n / (n - p) (J^T J)^-1 (sum_k r_k^2 J_k^T J_k) (J^T J)^-1,
// which does not assume every residual has the same variance: the samples' shot noise grows with
// R, and a misfit of the model concentrates where the lobe is. (J^T J)^-1 is a pseudo-inverse, so
// a direction the data do not constrain gets variance 0 rather than infinity: callers treat a
// parameter whose column is zero as not known. A fit with n <= p returns NaN.
//
// `neighbours` (optional, one list per residual of (other residual, kernel weight)) makes it the
// heteroscedasticity-and-autocorrelation-consistent form (Newey and West 1987): the meat also sums
// w_kl r_k r_l J_k^T J_l over neighbouring samples, because a misfit of the model is smooth from
// dot to dot and its residuals are not independent.
using Neighbours = std::vector<std::vector<std::pair<int, double>>>;

inline Eigen::MatrixXd SandwichCovariance(const Eigen::MatrixXd& jacobian, const Eigen::VectorXd& residuals,
                                          const Neighbours* neighbours = nullptr) {
  const Eigen::Index n = jacobian.rows(), p = jacobian.cols();
  if (n <= p) return Eigen::MatrixXd::Constant(p, p, std::numeric_limits<double>::quiet_NaN());
  const Eigen::MatrixXd bread = (jacobian.transpose() * jacobian).completeOrthogonalDecomposition().pseudoInverse();
  // Scores s_k = r_k J_k, one sample per row, padded to a multiple of 8 so that a neighbour's
  // contribution below is whole vector operations; meat = sum_k s_k (s_k + sum_l w_kl s_l)^T.
  constexpr Eigen::Index kLanes = 8;
  const Eigen::Index stride = (p + kLanes - 1) / kLanes * kLanes;
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  RowMajor scores = RowMajor::Zero(n, stride);
  scores.leftCols(p) = residuals.asDiagonal() * jacobian;
  RowMajor summed = scores;  // s_k + sum_l w_kl s_l
  if (neighbours && static_cast<Eigen::Index>(neighbours->size()) == n) {
    // A sample has about 28 neighbours at 3 dot spacings.
    for (Eigen::Index k = 0; k < n; ++k) {
      for (Eigen::Index block = 0; block < stride; block += kLanes) {
        // Summed in a fixed-size block, which Eigen keeps in vector registers (a store through a
        // pointer for every neighbour could alias the scores it reads, and kept the loop scalar).
        using Lanes = Eigen::Matrix<double, kLanes, 1>;
        Lanes sum = Lanes::Zero();
        for (const auto& [l, w] : (*neighbours)[k]) {
          sum += w * Eigen::Map<const Lanes>(scores.data() + static_cast<Eigen::Index>(l) * stride + block);
        }
        Eigen::Map<Lanes>(summed.data() + k * stride + block) += sum;
      }
    }
  }
  // S^T S + S^T W S, the cross terms symmetrised: S^T S + (S^T W S + S^T W^T S) / 2.
  const Eigen::MatrixXd product = (scores.transpose() * summed).topLeftCorner(p, p);
  const Eigen::MatrixXd meat = 0.5 * (product + product.transpose());
  return static_cast<double>(n) / static_cast<double>(n - p) * bread * meat * bread;
}

// The neighbours of a slice's samples in the store's dot grid: dots within `radius` of each other
// on the monitor, with the Bartlett weight 1 - distance / (radius + spacing). `dot_neighbours`
// lists them per dot (computed once per store), `dots` is the slice's dot index per sample.
inline Neighbours SampleNeighbours(const std::vector<std::vector<std::pair<int, double>>>& dot_neighbours,
                                   const std::vector<int>& dots, std::vector<int>* sample_of_dot) {
  Neighbours result(dots.size());
  if (dot_neighbours.empty()) return result;
  sample_of_dot->assign(dot_neighbours.size(), -1);
  for (size_t k = 0; k < dots.size(); ++k) (*sample_of_dot)[dots[k]] = static_cast<int>(k);
  for (size_t k = 0; k < dots.size(); ++k) {
    for (const auto& [q, w] : dot_neighbours[dots[k]]) {
      const int l = (*sample_of_dot)[q];
      if (l >= 0) result[k].emplace_back(l, w);
    }
  }
  return result;
}

// sqrt of a variance, NaN and negative round-off mapped to -1 (not known).
inline double StandardError(double variance) {
  return std::isfinite(variance) && variance >= 0 ? std::sqrt(variance) : -1.0;
}

// Bartlett-weighted neighbours of points (any dimension) within radius spacings of each other, the
// spacing the median nearest-neighbour distance; for one slice or one dot grid. Each list is in
// increasing index order.
//
// A sweep over the points in order of their first coordinate: two points farther apart along it
// than a distance sought are farther apart than that, so each search stops there. (Every pair
// was compared before: at 1,600 samples that was 4% of a representative's fit.) Points with a
// coordinate that is not finite cannot be ordered; then every pair is compared, as before.
template <typename Point>
std::vector<std::vector<std::pair<int, double>>> PointNeighbours(const std::vector<Point>& points, double radius) {
  const size_t n = points.size();
  std::vector<std::vector<std::pair<int, double>>> result(n);
  if (n < 2 || !(radius > 0)) return result;
  const bool finite = std::all_of(points.begin(), points.end(), [](const Point& p) { return p.allFinite(); });
  std::vector<size_t> order(n);
  for (size_t i = 0; i < n; ++i) order[i] = i;
  if (finite) std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return points[a][0] < points[b][0]; });
  // Calls visit(b, distance) for every other point b that may lie within `reach` of point
  // order[i] (all of them when the points are not finite); `reach` may shrink as it goes. The
  // margin keeps a pair whose rounded distance falls just below its rounded offset.
  const auto visit_near = [&](size_t i, const double& reach, const auto& visit) {
    const size_t a = order[i];
    const auto beyond = [&](size_t j) {
      return finite && std::abs(points[order[j]][0] - points[a][0]) > reach * (1.0 + 1e-9);
    };
    for (size_t j = i + 1; j < n && !beyond(j); ++j) visit(order[j], (points[a] - points[order[j]]).norm());
    for (size_t j = i; j-- > 0 && !beyond(j);) visit(order[j], (points[a] - points[order[j]]).norm());
  };
  std::vector<double> nearest(n, std::numeric_limits<double>::infinity());
  for (size_t i = 0; i < n; ++i) {
    double& best = nearest[order[i]];
    visit_near(i, best, [&](size_t, double d) { best = std::min(best, d); });
  }
  std::vector<double> sorted = nearest;
  std::nth_element(sorted.begin(), sorted.begin() + n / 2, sorted.end());
  const double spacing = sorted[n / 2];
  if (!(spacing > 0) || !std::isfinite(spacing)) return result;
  const double reach = radius * spacing * 1.01, bandwidth = (radius + 1.0) * spacing;
  for (size_t i = 0; i < n; ++i) {
    std::vector<std::pair<int, double>>& list = result[order[i]];
    visit_near(i, reach, [&](size_t b, double d) {
      if (d <= reach) list.emplace_back(static_cast<int>(b), 1.0 - d / bandwidth);
    });
    std::sort(list.begin(), list.end());
  }
  return result;
}

}  // namespace svbtdf::fit
