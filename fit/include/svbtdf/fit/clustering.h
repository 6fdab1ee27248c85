#pragma once
// Clustering of BTDF slices (Dai et al. 2009 Sec. 4.3, after Wang et al. 2008): only a few
// representative texels are fitted; every texel is then an affine combination of nearby
// representatives' slices, and the same weights interpolate their fitted parameters.
//
// Slices are compared after a PCA reduction (the components come from a random subsample, the
// projections stream over all texels), k-means++ seeds on a subsample, Lloyd iterations compare
// a texel with every centre (by blocked matrix products) only where Hamerly's bounds cannot rule
// the other centres out, so that 360,000 texels x 3,072 cells cluster in seconds.

#include <cstdint>
#include <functional>
#include <utility>
#include <vector>

namespace svbtdf::fit {

// Where the slices come from: texel t's slice is written into `out` (dimension floats).
struct SliceSource {
  int64_t num_texels = 0;
  int dimension = 0;
  std::function<void(int64_t texel, float* out)> read;
};

struct ClusteringOptions {
  double representative_fraction = 0.01;  // the paper's 1%
  int min_representatives = 1;
  int pca_dimensions = 16;
  int pca_subsample = 20000;        // texels used to estimate the principal components
  int seeding_subsample = 50000;    // texels k-means++ seeds from
  int kmeans_iterations = 15;
  int neighbours = 6;               // representatives per affine combination
  double weight_regularization = 1e-4;  // Tikhonov term (relative) keeping the weights bounded
  uint64_t seed = 1;
  int threads = 0;                  // 0: all hardware threads
  // Compare every texel with every centre on every k-means pass, the reference for the bounds
  // that skip most of those comparisons (tests, bench/bench_cluster.cc); the result is the same.
  bool exhaustive_assignment = false;
  // A progress bar over the passes (projection, seeding, each k-means iteration, the weights):
  // at paper scale the clustering takes minutes (docs/benchmarks.md, "scaling.py").
  bool progress = false;
};

struct AffineWeights {
  std::vector<std::pair<int, float>> terms;  // (representative index, weight); weights sum to 1
};

struct Clustering {
  std::vector<int64_t> representatives;  // texel index of each representative
  std::vector<int> cluster;              // per texel: its k-means cluster (= representative index)
  std::vector<AffineWeights> weights;    // per texel
  double explained_variance = 0.0;       // fraction of the subsample's variance the PCA keeps
};

// Throws svbtdf::Error(kInvalidInput) for an empty source or bad options.
Clustering ClusterSlices(const SliceSource& source, const ClusteringOptions& options = {});

// Affine weights (sum 1) that best reproduce `target` from `basis` vectors, with a small
// Tikhonov regularisation toward equal weights. Exposed for tests.
std::vector<double> SolveAffineWeights(const std::vector<std::vector<float>>& basis,
                                       const std::vector<float>& target, double regularization);

}  // namespace svbtdf::fit
