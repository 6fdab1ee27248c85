// Tests of the slice clustering and the affine interpolation weights (paper Sec. 4.3).
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>

#include "svbtdf/common/error.h"
#include "svbtdf/common/progress.h"
#include "svbtdf/fit/clustering.h"
#include "svbtdf/model/vec.h"

namespace svbtdf::fit {
namespace {

// A synthetic material: `types` distinct slice shapes (Gaussian bumps at different places of a
// 1-D stand-in for the light hemicube), each texel one of them scaled a little, plus noise.
struct SyntheticSlices {
  int dimension = 256;
  std::vector<std::vector<float>> slices;
  std::vector<int> type;
};

SyntheticSlices MakeSlices(int types, int per_type, double noise, uint64_t seed) {
  SyntheticSlices s;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss(0, 1);
  std::uniform_real_distribution<double> uniform(0.9, 1.1);
  for (int t = 0; t < types; ++t) {
    const double centre = (t + 0.5) * s.dimension / types, width = 6.0 + 2.0 * t;
    for (int k = 0; k < per_type; ++k) {
      std::vector<float> slice(s.dimension);
      const double scale = uniform(rng);
      for (int d = 0; d < s.dimension; ++d) {
        slice[d] = static_cast<float>(scale * std::exp(-0.5 * model::Square((d - centre) / width)) + noise * gauss(rng));
      }
      s.slices.push_back(slice);
      s.type.push_back(t);
    }
  }
  return s;
}

SliceSource SourceOf(const SyntheticSlices& s) {
  SliceSource source;
  source.num_texels = static_cast<int64_t>(s.slices.size());
  source.dimension = s.dimension;
  source.read = [&s](int64_t t, float* out) { std::copy(s.slices[t].begin(), s.slices[t].end(), out); };
  return source;
}

TEST(Clustering, GroupsTexelsOfTheSameSliceTypeAndPicksMembersAsRepresentatives) {
  const SyntheticSlices s = MakeSlices(5, 400, 0.01, 3);
  ClusteringOptions options;
  options.representative_fraction = 0.01;  // 20 representatives for 2,000 texels
  const Clustering c = ClusterSlices(SourceOf(s), options);
  ASSERT_EQ(c.representatives.size(), 20u);
  EXPECT_GT(c.explained_variance, 0.9);
  // Every cluster is pure: all its texels share the representative's slice type.
  int impure = 0;
  for (size_t t = 0; t < s.slices.size(); ++t) {
    impure += s.type[t] != s.type[c.representatives[c.cluster[t]]];
  }
  EXPECT_EQ(impure, 0);
  // Every type has at least one representative.
  std::map<int, int> types;
  for (int64_t r : c.representatives) ++types[s.type[r]];
  EXPECT_EQ(types.size(), 5u);
}

// Hamerly's bounds skip comparisons, never change the answer: with more clusters than slice
// types (so that many texels lie near a boundary between clusters of one type) and noisy
// slices, the bounded k-means gives the clusters, representatives and weights of comparing
// every texel with every centre on every pass.
TEST(Clustering, BoundsGiveTheClustersOfComparingEveryTexelWithEveryCentre) {
  const SyntheticSlices s = MakeSlices(12, 250, 0.05, 11);
  for (const double fraction : {0.002, 0.05, 0.2}) {  // 6, 150 and 600 clusters of 3,000 texels
    ClusteringOptions options;
    options.representative_fraction = fraction;
    options.exhaustive_assignment = true;
    const Clustering every = ClusterSlices(SourceOf(s), options);
    options.exhaustive_assignment = false;
    const Clustering bounded = ClusterSlices(SourceOf(s), options);
    EXPECT_EQ(bounded.representatives, every.representatives) << fraction;
    EXPECT_EQ(bounded.cluster, every.cluster) << fraction;
    ASSERT_EQ(bounded.weights.size(), every.weights.size());
    int64_t differ = 0;
    for (size_t t = 0; t < every.weights.size(); ++t) differ += bounded.weights[t].terms != every.weights[t].terms;
    EXPECT_EQ(differ, 0) << fraction;
  }
}

// At paper scale the clustering takes about a minute before the first fit: its bar counts the
// projection, the seeding, each k-means pass and the weights, and ends full.
TEST(Clustering, ShowsItsPassesOnAProgressBar) {
  const SyntheticSlices s = MakeSlices(3, 100, 0.01, 4);
  ClusteringOptions options;
  options.representative_fraction = 0.05;
  options.kmeans_iterations = 4;
  options.progress = true;
  std::vector<std::pair<int64_t, int64_t>> reports;
  common::ProgressBar::SetEnabled(false);
  common::ProgressBar::SetObserver([&](const std::string& label, int64_t done, int64_t total) {
    if (label == "cluster") reports.emplace_back(done, total);
  });
  ClusterSlices(SourceOf(s), options);
  options.progress = false;
  const size_t with_bar = reports.size();
  ClusterSlices(SourceOf(s), options);
  common::ProgressBar::SetObserver({});
  common::ProgressBar::SetEnabled(true);
  ASSERT_GE(with_bar, 2u);
  EXPECT_EQ(reports.size(), with_bar);  // no bar unless asked for
  EXPECT_EQ(reports.back(), std::make_pair(int64_t{7}, int64_t{7}));  // 4 passes + 3
}

TEST(Clustering, AffineWeightsSumToOneAndBeatTheNearestRepresentative) {
  // Texels that blend two slice types: their nearest representative alone is a poor stand-in,
  // an affine combination of nearby representatives a good one.
  SyntheticSlices s = MakeSlices(3, 300, 0.002, 5);
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> uniform(0, 1);
  const size_t pure = s.slices.size();
  for (int k = 0; k < 300; ++k) {
    const size_t a = rng() % pure, b = rng() % pure;
    const double w = uniform(rng);
    std::vector<float> mix(s.dimension);
    for (int d = 0; d < s.dimension; ++d) mix[d] = static_cast<float>(w * s.slices[a][d] + (1 - w) * s.slices[b][d]);
    s.slices.push_back(mix);
    s.type.push_back(-1);
  }
  ClusteringOptions options;
  options.representative_fraction = 0.03;
  options.pca_dimensions = 24;
  const Clustering c = ClusterSlices(SourceOf(s), options);
  double affine_error = 0, nearest_error = 0;
  for (size_t t = 0; t < s.slices.size(); ++t) {
    double sum = 0;
    std::vector<double> reconstruction(s.dimension, 0.0);
    for (const auto& [rep, w] : c.weights[t].terms) {
      sum += w;
      for (int d = 0; d < s.dimension; ++d) reconstruction[d] += w * s.slices[c.representatives[rep]][d];
    }
    EXPECT_NEAR(sum, 1.0, 1e-5);
    if (s.type[t] >= 0) continue;
    const auto& nearest = s.slices[c.representatives[c.cluster[t]]];
    for (int d = 0; d < s.dimension; ++d) {
      affine_error += model::Square(reconstruction[d] - s.slices[t][d]);
      nearest_error += model::Square(nearest[d] - s.slices[t][d]);
    }
  }
  EXPECT_LT(affine_error, 0.5 * nearest_error) << "affine " << affine_error << " nearest " << nearest_error;
}

TEST(Clustering, SolveAffineWeightsReproducesAnAffineCombinationExactly) {
  const std::vector<std::vector<float>> basis = {{1, 0, 0, 2}, {0, 1, 0, 1}, {0, 0, 1, -1}};
  std::vector<float> target(4);
  const double w[3] = {0.5, 0.8, -0.3};
  for (int d = 0; d < 4; ++d) target[d] = static_cast<float>(w[0] * basis[0][d] + w[1] * basis[1][d] + w[2] * basis[2][d]);
  const std::vector<double> solved = SolveAffineWeights(basis, target, 1e-9);
  for (int j = 0; j < 3; ++j) EXPECT_NEAR(solved[j], w[j], 1e-5);
}

TEST(Clustering, RejectsAnEmptySourceAndBadFractions) {
  EXPECT_THROW(ClusterSlices(SliceSource{}), common::Error);
  const SyntheticSlices s = MakeSlices(2, 10, 0.0, 1);
  ClusteringOptions options;
  options.representative_fraction = 0.0;
  EXPECT_THROW(ClusterSlices(SourceOf(s), options), common::Error);
}

}  // namespace
}  // namespace svbtdf::fit
