#include "svbtdf/fit/clustering.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <random>
#include <string>
#include <thread>

#include "svbtdf/common/error.h"
#include "svbtdf/common/progress.h"
#include "svbtdf/common/interrupt.h"
#include "svbtdf/common/parallel.h"

namespace svbtdf::fit {
namespace {

using MatrixF = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using VectorF = Eigen::VectorXf;

std::vector<int64_t> RandomSubset(int64_t n, int64_t m, std::mt19937_64& rng) {
  std::vector<int64_t> all(n);
  std::iota(all.begin(), all.end(), 0);
  if (m >= n) return all;
  for (int64_t k = 0; k < m; ++k) {  // partial Fisher-Yates
    std::uniform_int_distribution<int64_t> pick(k, n - 1);
    std::swap(all[k], all[pick(rng)]);
  }
  all.resize(m);
  std::sort(all.begin(), all.end());
  return all;
}

struct Pca {
  VectorF mean;
  MatrixF components;  // dimension x p, orthonormal columns
  double explained_variance = 0.0;
};

// Top principal components of a subsample by a randomised range finder (Halko et al. 2011):
// O(m d p) instead of the O(m d^2) of a covariance matrix.
Pca ComputePca(const SliceSource& source, const ClusteringOptions& options, std::mt19937_64& rng) {
  const std::vector<int64_t> subset = RandomSubset(source.num_texels, options.pca_subsample, rng);
  const int64_t m = static_cast<int64_t>(subset.size());
  const int d = source.dimension;
  MatrixF x(m, d);
  for (int64_t r = 0; r < m; ++r) source.read(subset[r], x.row(r).data());
  Pca pca;
  pca.mean = x.colwise().mean().transpose();
  x.rowwise() -= pca.mean.transpose();
  const int p = std::min<int>({options.pca_dimensions, d, static_cast<int>(m)});
  const int sketch = std::min<int>(p + 10, std::min<int>(d, static_cast<int>(m)));
  std::normal_distribution<float> gauss(0.0f, 1.0f);
  MatrixF omega(d, sketch);
  for (int r = 0; r < d; ++r) {
    for (int c = 0; c < sketch; ++c) omega(r, c) = gauss(rng);
  }
  Eigen::MatrixXf y = x * omega;
  for (int power = 0; power < 2; ++power) {  // two power iterations sharpen the spectrum
    Eigen::HouseholderQR<Eigen::MatrixXf> qr(y);
    const Eigen::MatrixXf q = qr.householderQ() * Eigen::MatrixXf::Identity(y.rows(), sketch);
    y = x * (x.transpose() * q);
  }
  Eigen::HouseholderQR<Eigen::MatrixXf> qr(y);
  const Eigen::MatrixXf q = qr.householderQ() * Eigen::MatrixXf::Identity(y.rows(), sketch);
  const Eigen::MatrixXf b = q.transpose() * x;  // sketch x d
  Eigen::BDCSVD<Eigen::MatrixXf> svd(b, Eigen::ComputeThinV);
  pca.components = svd.matrixV().leftCols(p);
  const double total = x.squaredNorm();
  const double kept = svd.singularValues().head(p).squaredNorm();
  pca.explained_variance = total > 0 ? kept / total : 1.0;
  return pca;
}

MatrixF ProjectAll(const SliceSource& source, const Pca& pca, int threads) {
  const int p = static_cast<int>(pca.components.cols());
  MatrixF z(source.num_texels, p);
  common::ParallelFor(source.num_texels, threads, (source.num_texels + threads - 1) / threads, [&](int64_t begin, int64_t end) {
    VectorF slice(source.dimension);
    for (int64_t t = begin; t < end; ++t) {
      source.read(t, slice.data());
      z.row(t) = ((slice - pca.mean).transpose() * pca.components);
    }
  });
  return z;
}

// Squared distances between rows of `points` [begin, end) and all `centres`, by ||a||^2 - 2ab + ||b||^2.
MatrixF BlockDistances(const MatrixF& points, int64_t begin, int64_t end, const MatrixF& centres,
                       const VectorF& centre_norms) {
  const auto block = points.middleRows(begin, end - begin);
  MatrixF distances = -2.0f * (block * centres.transpose());
  const VectorF norms = block.rowwise().squaredNorm();
  distances.colwise() += norms;
  distances.rowwise() += centre_norms.transpose();
  return distances;
}

MatrixF SeedKMeansPlusPlus(const MatrixF& z, int k, const ClusteringOptions& options, std::mt19937_64& rng) {
  const std::vector<int64_t> subset = RandomSubset(z.rows(), std::max<int64_t>(options.seeding_subsample, k), rng);
  const int64_t s = static_cast<int64_t>(subset.size());
  MatrixF centres(k, z.cols());
  std::uniform_int_distribution<int64_t> first(0, s - 1);
  centres.row(0) = z.row(subset[first(rng)]);
  std::vector<double> nearest(s, std::numeric_limits<double>::infinity());
  for (int c = 1; c < k; ++c) {
    double total = 0.0;
    for (int64_t r = 0; r < s; ++r) {
      nearest[r] = std::min<double>(nearest[r], (z.row(subset[r]) - centres.row(c - 1)).squaredNorm());
      total += nearest[r];
    }
    int64_t chosen = first(rng);
    if (total > 0) {
      std::uniform_real_distribution<double> uniform(0.0, total);
      double target = uniform(rng);
      for (chosen = 0; chosen < s - 1 && (target -= nearest[chosen]) > 0; ++chosen) {
      }
    }
    centres.row(c) = z.row(subset[chosen]);
  }
  return centres;
}

// Where the smallest of `values` is: its value by a vectorised reduction, then its place.
template <typename Row>
int IndexOfMinimum(const Row& values) {
  const float smallest = values.minCoeff();
  int i = 0;
  while (i + 1 < values.size() && !(values[i] == smallest)) ++i;
  return i;
}

// Each point's centre, as Lloyd's k-means needs it after every move of the centres. Comparing
// every point with every centre costs N k per pass, and the centres are a fixed fraction of the
// points, so that grows as the square of the texels (docs/benchmarks.md, "scaling.py"). Hamerly's
// bounds (2010) skip part of it: a point keeps its centre without the comparison while its
// distance to that centre is below both half the distance from the centre to the nearest other
// centre and a lower bound on its distance to every other centre (the second-nearest distance
// of its last full comparison, less the most any other centre has moved since). The answer is
// the full comparison's. At paper scale they skip only 30-40% of the comparisons, because a few
// of the thousands of centres keep moving far and the one bound drops by their move
// (docs/benchmarks.md, "bench_cluster"); bounds per group of centres would keep more.
class CentreAssignment {
 public:
  CentreAssignment(const MatrixF& z, int threads) : z_(z), threads_(threads) {
    label_.assign(z.rows(), 0);
    distance_.assign(z.rows(), 0.0f);
    lower_.assign(z.rows(), 0.0f);
  }

  // Assigns every point its nearest centre. `previous` are the centres of the last call (empty
  // on the first, or to compare every point with every centre).
  void Assign(const MatrixF& centres, const MatrixF& previous) {
    centre_norms_ = centres.rowwise().squaredNorm();
    largest_centre_norm_ = centre_norms_.size() > 0 ? centre_norms_.maxCoeff() : 0.0f;
    const bool bounded = previous.rows() == centres.rows() && centres.rows() > 1;
    if (bounded) PrepareBounds(centres, previous);
    constexpr int64_t kBlock = 2048;
    const int64_t n = z_.rows(), blocks = (n + kBlock - 1) / kBlock;
    common::ParallelFor(blocks, threads_, (blocks + threads_ - 1) / threads_, [&](int64_t block_begin, int64_t block_end) {
      std::vector<int64_t> unsure;
      for (int64_t b = block_begin; b < block_end; ++b) {
        unsure.clear();
        for (int64_t t = b * kBlock; t < std::min(n, (b + 1) * kBlock); ++t) {
          if (!bounded || !KeepsItsCentre(t, centres)) unsure.push_back(t);
        }
        CompareWithEveryCentre(unsure, centres);
      }
    });
  }

  const std::vector<int>& label() const { return label_; }
  // Squared distance of each point to its centre, exact (not from the bounds).
  std::vector<float>& distance() { return distance_; }

 private:
  // The slack in a squared distance computed as |a|^2 - 2 a.b + |b|^2 in single precision,
  // relative to |a|^2 + |b|^2: the sixteen-term dot product and the cancellation are good to a
  // few 1e-7 of it. The bounds give it away, so that rounding never lets a point keep a centre
  // that another beats.
  static constexpr float kExpansionSlack = 1e-5f;

  void PrepareBounds(const MatrixF& centres, const MatrixF& previous) {
    const int k = static_cast<int>(centres.rows());
    drift_ = (centres - previous).rowwise().norm();
    farthest_ = 0;
    for (int c = 1; c < k; ++c) {
      if (drift_[c] > drift_[farthest_]) farthest_ = c;
    }
    second_drift_ = 0.0f;
    for (int c = 0; c < k; ++c) {
      if (c != farthest_) second_drift_ = std::max(second_drift_, drift_[c]);
    }
    // Half the distance from each centre to its nearest other centre, blocked over the centres.
    half_gap_.resize(k);
    const float slack = kExpansionSlack * 2.0f * largest_centre_norm_;
    constexpr int64_t kBlock = 256;
    const int64_t blocks = (k + kBlock - 1) / kBlock;
    common::ParallelFor(blocks, threads_, (blocks + threads_ - 1) / threads_, [&](int64_t block_begin, int64_t block_end) {
      for (int64_t b = block_begin; b < block_end; ++b) {
        const int64_t begin = b * kBlock, end = std::min<int64_t>(k, begin + kBlock);
        const MatrixF d = BlockDistances(centres, begin, end, centres, centre_norms_);
        for (int64_t c = begin; c < end; ++c) {
          float nearest = std::numeric_limits<float>::infinity();
          for (int other = 0; other < k; ++other) {
            if (other != c) nearest = std::min(nearest, d(c - begin, other));
          }
          half_gap_[c] = 0.5f * std::sqrt(std::max(0.0f, nearest - slack));
        }
      }
    });
  }

  // Moves point t's bound by the centres' drift and its distance to its own centre to their new
  // places; true when no other centre can be nearer.
  bool KeepsItsCentre(int64_t t, const MatrixF& centres) {
    const int c = label_[t];
    lower_[t] = std::max(0.0f, lower_[t] - (c == farthest_ ? second_drift_ : drift_[farthest_]));
    distance_[t] = (z_.row(t) - centres.row(c)).squaredNorm();
    return std::sqrt(distance_[t]) < std::max(half_gap_[c], lower_[t]);
  }

  // The full comparison of the points `rows` with every centre: the nearest, its exact squared
  // distance, and a lower bound on the distance to any other.
  void CompareWithEveryCentre(const std::vector<int64_t>& rows, const MatrixF& centres) {
    if (rows.empty()) return;
    const int k = static_cast<int>(centres.rows());
    MatrixF block(static_cast<Eigen::Index>(rows.size()), z_.cols());
    for (size_t r = 0; r < rows.size(); ++r) block.row(static_cast<Eigen::Index>(r)) = z_.row(rows[r]);
    MatrixF d = BlockDistances(block, 0, block.rows(), centres, centre_norms_);
    for (size_t r = 0; r < rows.size(); ++r) {
      const int64_t t = rows[r];
      // The nearest and the second nearest by two minimum searches, each a vectorised reduction
      // and a scan for where its value is (one branchy loop keeping both took 60% of the
      // clustering at 600 x 600 texels).
      auto row = d.row(static_cast<Eigen::Index>(r));
      int best = IndexOfMinimum(row), second = -1;
      if (k > 1) {
        row[best] = std::numeric_limits<float>::infinity();
        second = IndexOfMinimum(row);
      }
      float best_exact = (z_.row(t) - centres.row(best)).squaredNorm();
      if (second < 0) {  // one centre
        label_[t] = best, distance_[t] = best_exact, lower_[t] = std::numeric_limits<float>::infinity();
        continue;
      }
      float second_exact = (z_.row(t) - centres.row(second)).squaredNorm();
      if (second_exact < best_exact) std::swap(best, second), std::swap(best_exact, second_exact);
      const float slack = kExpansionSlack * (z_.row(t).squaredNorm() + largest_centre_norm_);
      label_[t] = best;
      distance_[t] = best_exact;
      lower_[t] = std::sqrt(std::max(0.0f, second_exact - slack));
    }
  }

  const MatrixF& z_;
  const int threads_;
  std::vector<int> label_;
  std::vector<float> distance_;
  std::vector<float> lower_;  // per point: no centre but its own is nearer than this
  VectorF centre_norms_;
  float largest_centre_norm_ = 0.0f;
  VectorF drift_;      // per centre: how far it moved since the last assignment
  int farthest_ = 0;   // the centre that moved most
  float second_drift_ = 0.0f;  // the most any other centre moved
  std::vector<float> half_gap_;
};

}  // namespace

std::vector<double> SolveAffineWeights(const std::vector<std::vector<float>>& basis,
                                       const std::vector<float>& target, double regularization) {
  const int m = static_cast<int>(basis.size());
  if (m == 0) common::ThrowInvalidInput("affine weights", "no basis slices");
  const int d = static_cast<int>(target.size());
  Eigen::MatrixXd b(d, m);
  for (int j = 0; j < m; ++j) {
    if (static_cast<int>(basis[j].size()) != d) common::ThrowInvalidInput("affine weights", "basis sizes differ");
    for (int r = 0; r < d; ++r) b(r, j) = basis[j][r];
  }
  Eigen::VectorXd t(d);
  for (int r = 0; r < d; ++r) t[r] = target[r];
  // KKT system of min |B w - t|^2 + lambda |w - 1/m|^2 subject to sum(w) = 1.
  const Eigen::MatrixXd gram = b.transpose() * b;
  const double lambda = regularization * std::max(gram.trace() / m, 1e-30);
  Eigen::MatrixXd kkt = Eigen::MatrixXd::Zero(m + 1, m + 1);
  kkt.topLeftCorner(m, m) = gram + lambda * Eigen::MatrixXd::Identity(m, m);
  kkt.block(0, m, m, 1).setOnes();
  kkt.block(m, 0, 1, m).setOnes();
  Eigen::VectorXd rhs(m + 1);
  rhs.head(m) = b.transpose() * t + Eigen::VectorXd::Constant(m, lambda / m);
  rhs[m] = 1.0;
  const Eigen::VectorXd solution = kkt.fullPivLu().solve(rhs);
  return std::vector<double>(solution.data(), solution.data() + m);
}

Clustering ClusterSlices(const SliceSource& source, const ClusteringOptions& options) {
  if (source.num_texels <= 0 || source.dimension <= 0 || !source.read) {
    common::ThrowInvalidInput("clustering", "no slices to cluster");
  }
  if (!(options.representative_fraction > 0 && options.representative_fraction <= 1)) {
    common::ThrowInvalidInput("--representatives", "the fraction must lie in (0, 1]");
  }
  const int threads = common::ThreadCount(options.threads);
  std::mt19937_64 rng(options.seed);
  const int64_t n = source.num_texels;
  const int k = static_cast<int>(std::clamp<int64_t>(
      std::llround(options.representative_fraction * n), std::max(1, options.min_representatives), n));

  std::unique_ptr<common::ProgressBar> progress;
  if (options.progress) progress = std::make_unique<common::ProgressBar>("cluster", options.kmeans_iterations + 3, "passes");
  const auto advance = [&] {
    if (progress) progress->Advance();
  };
  const Pca pca = ComputePca(source, options, rng);
  const MatrixF z = ProjectAll(source, pca, threads);
  common::ThrowIfInterrupted("clustering");
  advance();

  MatrixF centres = SeedKMeansPlusPlus(z, k, options, rng);
  advance();
  CentreAssignment assignment(z, threads);
  MatrixF previous;  // the centres of the last assignment; none: compare with every centre
  for (int iteration = 0; iteration <= options.kmeans_iterations; ++iteration) {
    assignment.Assign(centres, options.exhaustive_assignment ? MatrixF() : previous);
    if (iteration == options.kmeans_iterations) break;  // the last pass assigns the final centres
    const std::vector<int>& label = assignment.label();
    std::vector<float>& distance = assignment.distance();
    MatrixF sums = MatrixF::Zero(k, z.cols());
    std::vector<int64_t> counts(k, 0);
    for (int64_t t = 0; t < n; ++t) {
      sums.row(label[t]) += z.row(t);
      ++counts[label[t]];
    }
    previous = centres;
    for (int c = 0; c < k; ++c) {
      if (counts[c] > 0) {
        centres.row(c) = sums.row(c) / static_cast<float>(counts[c]);
      } else {  // an empty cluster restarts at the point worst served so far
        const int64_t worst = std::max_element(distance.begin(), distance.end()) - distance.begin();
        centres.row(c) = z.row(worst);
        distance[worst] = 0.0f;
      }
    }
    common::ThrowIfInterrupted("clustering");
    advance();
  }
  const std::vector<int>& label = assignment.label();
  const std::vector<float>& distance = assignment.distance();

  // The representative of a cluster is its member nearest the centre.
  Clustering result;
  result.explained_variance = pca.explained_variance;
  std::vector<int64_t> nearest_member(k, -1);
  for (int64_t t = 0; t < n; ++t) {
    const int c = label[t];
    if (nearest_member[c] < 0 || distance[t] < distance[nearest_member[c]]) nearest_member[c] = t;
  }
  std::vector<int> representative_of_cluster(k, -1);
  for (int c = 0; c < k; ++c) {
    if (nearest_member[c] < 0) continue;
    representative_of_cluster[c] = static_cast<int>(result.representatives.size());
    result.representatives.push_back(nearest_member[c]);
  }
  const int r = static_cast<int>(result.representatives.size());
  MatrixF rep_z(r, z.cols());
  for (int j = 0; j < r; ++j) rep_z.row(j) = z.row(result.representatives[j]);
  result.cluster.resize(n);
  for (int64_t t = 0; t < n; ++t) result.cluster[t] = representative_of_cluster[label[t]];

  // Affine weights over the nearest representatives, in PCA space.
  result.weights.resize(n);
  const int neighbours = std::min(options.neighbours, r);
  std::vector<int> rep_index_of_texel(n, -1);
  for (int j = 0; j < r; ++j) rep_index_of_texel[result.representatives[j]] = j;
  const VectorF rep_norms = rep_z.rowwise().squaredNorm();
  constexpr int64_t kBlock = 1024;
  const int64_t blocks = (n + kBlock - 1) / kBlock;
  common::ParallelFor(blocks, threads, (blocks + threads - 1) / threads, [&](int64_t block_begin, int64_t block_end) {
    std::vector<int> order(r);
    for (int64_t b = block_begin; b < block_end; ++b) {
      const int64_t begin = b * kBlock, end = std::min<int64_t>(n, begin + kBlock);
      const MatrixF d = BlockDistances(z, begin, end, rep_z, rep_norms);
      for (int64_t row = 0; row < end - begin; ++row) {
        const int64_t t = begin + row;
        if (rep_index_of_texel[t] >= 0) {
          result.weights[t].terms = {{rep_index_of_texel[t], 1.0f}};
          continue;
        }
        std::iota(order.begin(), order.end(), 0);
        std::partial_sort(order.begin(), order.begin() + neighbours, order.end(),
                          [&](int a, int c) { return d(row, a) < d(row, c); });
        // Centred coordinates: the mean cancels in an affine combination, and the small
        // PCA vectors keep the KKT system cheap.
        std::vector<std::vector<float>> basis(neighbours);
        for (int j = 0; j < neighbours; ++j) {
          basis[j].assign(rep_z.row(order[j]).data(), rep_z.row(order[j]).data() + z.cols());
        }
        const std::vector<float> target(z.row(t).data(), z.row(t).data() + z.cols());
        const std::vector<double> w = SolveAffineWeights(basis, target, options.weight_regularization);
        for (int j = 0; j < neighbours; ++j) result.weights[t].terms.emplace_back(order[j], static_cast<float>(w[j]));
      }
    }
  });
  advance();
  if (progress) progress->Finish();
  return result;
}

}  // namespace svbtdf::fit
