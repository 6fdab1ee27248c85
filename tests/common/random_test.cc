#include "svbtdf/common/random.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "chi_square.h"

namespace svbtdf::common {
namespace {

// A SplitMix64 counter: the 64-bit source the simulator's sensor noise uses.
struct CounterBits {
  uint64_t state;
  uint64_t operator()() { return SplitMix64(state += 0x9e3779b97f4a7c15ULL); }
};

double NormalCdf(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }

TEST(Random, ZigguratLayersHaveEqualAreaAndCloseAtTheTop) {
  const NormalZiggurat& z = TheNormalZiggurat();
  const double area = z.x[1] * z.f[1] + std::sqrt(std::acos(-1.0) / 2) * std::erfc(z.x[1] / std::sqrt(2.0));
  EXPECT_NEAR(z.x[0] * z.f[1], area, 1e-12);  // the base layer as a rectangle of its area
  // The top layer, closed at x = 0 by fiat, is short of the area by 2e-11 of its height: 1e-9
  // of the layer.
  for (int i = 1; i < NormalZiggurat::kLayers; ++i) {
    ASSERT_GT(z.x[i], z.x[i + 1]) << "layer " << i;
    EXPECT_NEAR(z.x[i] * (z.f[i + 1] - z.f[i]), area, i + 1 < NormalZiggurat::kLayers ? 1e-12 : 1e-11) << "layer " << i;
  }
  EXPECT_EQ(z.x[NormalZiggurat::kLayers], 0.0);
  EXPECT_EQ(z.f[NormalZiggurat::kLayers], 1.0);
}

// Four million variates binned 0.04 wide over [-5, 5] (the wedges' edges fall everywhere in
// it) and the two tails beyond: Pearson's chi-square against the normal distribution.
TEST(Random, StandardNormalPassesAChiSquareTest) {
  constexpr int kSamples = 4'000'000, kBins = 250;
  constexpr double kLimit = 5.0, kWidth = 2 * kLimit / kBins;
  CounterBits bits{12345};
  std::vector<double> observed(kBins + 2, 0.0), expected(kBins + 2, 0.0);
  double sum = 0, sum2 = 0, sum4 = 0;
  for (int n = 0; n < kSamples; ++n) {
    const double x = StandardNormal(bits);
    sum += x;
    sum2 += x * x;
    sum4 += x * x * x * x;
    if (x < -kLimit) {
      observed[kBins] += 1;
    } else if (x >= kLimit) {
      observed[kBins + 1] += 1;
    } else {
      observed[std::min(kBins - 1, static_cast<int>((x + kLimit) / kWidth))] += 1;
    }
  }
  for (int b = 0; b < kBins; ++b) expected[b] = kSamples * (NormalCdf(-kLimit + (b + 1) * kWidth) - NormalCdf(-kLimit + b * kWidth));
  expected[kBins] = expected[kBins + 1] = kSamples * NormalCdf(-kLimit);
  const testing::ChiSquareStatistic statistic = testing::PooledChiSquare(observed, expected);
  EXPECT_GT(statistic.bins, 200);
  EXPECT_LT(statistic.chi2, testing::ChiSquareBound(statistic.bins)) << "over " << statistic.bins << " bins";
  // Moments, each within 5 standard errors: mean 0 (se 1/sqrt(n)), variance 1 (se sqrt(2/n)),
  // fourth moment 3 (se sqrt(96/n)).
  EXPECT_NEAR(sum / kSamples, 0.0, 5 / std::sqrt(double(kSamples)));
  EXPECT_NEAR(sum2 / kSamples, 1.0, 5 * std::sqrt(2.0 / kSamples));
  EXPECT_NEAR(sum4 / kSamples, 3.0, 5 * std::sqrt(96.0 / kSamples));
}

// The tail beyond r, which only the base layer reaches, has the normal's mass and shape: counts
// beyond r, 4.5 and 5.5 in 20 million variates, each within 5 Poisson standard deviations.
TEST(Random, StandardNormalTailHasTheNormalsMass) {
  constexpr int kSamples = 20'000'000;
  const std::vector<double> edges = {NormalZiggurat::kTailStart, 4.5, 5.5};
  std::vector<double> beyond(edges.size(), 0.0);
  CounterBits bits{777};
  for (int n = 0; n < kSamples; ++n) {
    const double x = std::abs(StandardNormal(bits));
    for (size_t e = 0; e < edges.size(); ++e) beyond[e] += x > edges[e];
  }
  for (size_t e = 0; e < edges.size(); ++e) {
    const double expected = kSamples * 2 * NormalCdf(-edges[e]);
    EXPECT_NEAR(beyond[e], expected, 5 * std::sqrt(expected) + 1) << "|x| > " << edges[e];
  }
}

}  // namespace
}  // namespace svbtdf::common
