// Diffuse separation (EstimateDiffuse) and the dot-beneath flag (TexelsWithDotBeneath, reach.exr),
// from first principles: samples made from a known material with shot and read noise, and a rig
// whose view rays, continued through the sample, miss the dot grid on one side.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <vector>

#include <nlohmann/json.hpp>

#include "analytic_store.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/image_io.h"
#include "svbtdf/common/statistics.h"
#include "svbtdf/fit/slice_store.h"
#include "svbtdf/process/diffuse_separation.h"
#include "svbtdf/process/slice_store_writer.h"
#include "svbtdf/model/dual_microfacet.h"
#include "svbtdf/model/ggx.h"
#include "temp_folder.h"

namespace svbtdf::process {
using fit::SliceStore;
using fit::SliceStoreInfo;
using fit::TexelGeometry;
namespace {
namespace fs = std::filesystem;

// A fresh folder NAME inside this test program's temporary folder (removed at exit).
fs::path TestFolder(const std::string& name) {
  static const svbtdf::testing::TempFolder root("diffuse_test");
  return root.path() / name;
}

// A camera that records R through the measurement equation: the dot's light reaches the pixel as
// rate = R / s_q (s_q = r^2 / |i.z|, unit dot intensity), exposed in brackets of 1x and 16x a base
// time that puts the texel's brightest dot at 90% of a 40,000 e- well; Poisson shot noise
// (normal with the exact variance) and 3 e- read noise per image, saturated brackets dropped, and
// the brackets merged as the processing does (sum of values over sum of exposures).
class NoisyCamera {
 public:
  explicit NoisyCamera(uint64_t seed) : rng_(seed) {}

  // True R at every dot and its s_q -> measured R.
  std::vector<model::Rgb> Measure(const std::vector<model::Rgb>& truth, const std::vector<double>& scale) {
    double peak_rate = 0;
    for (size_t q = 0; q < truth.size(); ++q) peak_rate = std::max(peak_rate, model::Luminance(truth[q]) / scale[q]);
    const double base = 0.9 * kWell / peak_rate;  // electrons per unit rate at 1x
    std::vector<model::Rgb> out(truth.size());
    for (size_t q = 0; q < truth.size(); ++q) {
      for (int c = 0; c < 3; ++c) {
        double sum = 0, time = 0;
        for (double bracket : {1.0, 16.0}) {
          const double electrons = truth[q][c] / scale[q] * base * bracket;
          if (electrons >= kWell) continue;  // saturated
          sum += electrons + std::sqrt(electrons) * gauss_(rng_) + kReadNoise * gauss_(rng_);
          time += bracket;
        }
        out[q][c] = time > 0 ? sum / (time * base) * scale[q] : std::nan("");
      }
    }
    return out;
  }

 private:
  static constexpr double kWell = 40000.0, kReadNoise = 3.0;
  std::mt19937_64 rng_;
  std::normal_distribution<double> gauss_{0.0, 1.0};
};

// A texel's true R at every dot of `g` (texel 0) and each dot's s_q = r^2 / |i.z|: what
// NoisyCamera measures from.
struct TrueSamples {
  std::vector<model::Rgb> rho;
  std::vector<double> scale;
};

TrueSamples TrueSamplesOf(const TexelGeometry& g, const model::Ndf& ndf, const model::DualMicrofacetParams& params) {
  TrueSamples out;
  for (int q = 0; q < static_cast<int>(g.dots.size()); ++q) {
    const model::Vec3 to_dot = g.dots[q] - g.TexelCentre(0);
    out.rho.push_back(model::EvaluateMaterial(ndf, params, g.Light(0, q), g.View(0)));
    out.scale.push_back(to_dot.squaredNorm() / std::abs(to_dot.normalized().z()));
  }
  return out;
}

// The dual-microfacet parameters of these tests' texels: GGX 0.2 shadowing, k_s 0.8, eta 1.5.
model::DualMicrofacetParams TexelParams(const model::Rgb& rho_d) {
  model::DualMicrofacetParams params;
  params.eta = 1.5;
  params.alpha = 0.5;
  params.shadowing = model::SmithShadowing::Ggx(0.2);
  params.k_s = {0.8, 0.8, 0.8};
  params.rho_d = rho_d;
  return params;
}

// The paper's eq. 14 (the store's estimator before): per channel, the minimum R.
model::Rgb Minimum(const std::vector<model::Rgb>& r) {
  model::Rgb m = {1e300, 1e300, 1e300};
  for (const model::Rgb& v : r) {
    for (int c = 0; c < 3; ++c) m[c] = std::min(m[c], v[c]);
  }
  return m;
}

TEST(EstimateDiffuse, UnbiasedUnderShotNoiseWhereTheMinimumIsNot) {
  // The paper's rig (tests/support/analytic_store.h): 20 x 20 dots, one texel at the sample's
  // centre, a GGX 0.25 dual-microfacet lobe on a diffuse floor of 0.01.
  const calib::SessionCalibration calibration = testing::AnalyticCalibration(20);
  const TexelGeometry g = MakeTexelGeometry(calibration, 1, 1);
  const model::GgxNdf ndf(0.25, 0.25);
  const model::DualMicrofacetParams params = TexelParams({0.01, 0.012, 0.008});
  const auto [truth, scale] = TrueSamplesOf(g, ndf, params);
  // Noise-free, the floor is the diffuse term (the lobe's tails add a little).
  const std::vector<std::array<int, 2>> neighbour = OppositeNeighbours(g.dots);
  const DiffuseEstimate exact = EstimateDiffuse(truth, scale, neighbour);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(exact.rho_d[c] / params.rho_d[c], 1.0, 0.02) << c;

  NoisyCamera camera(3);
  constexpr int kTrials = 300;
  model::Rgb mean = {0, 0, 0}, mean_minimum = {0, 0, 0};
  std::vector<double> errors;
  for (int trial = 0; trial < kTrials; ++trial) {
    const std::vector<model::Rgb> measured = camera.Measure(truth, scale);
    const model::Rgb estimate = EstimateDiffuse(measured, scale, neighbour).rho_d;
    const model::Rgb minimum = Minimum(measured);
    for (int c = 0; c < 3; ++c) {
      mean[c] += estimate[c] / kTrials;
      mean_minimum[c] += minimum[c] / kTrials;
    }
    errors.push_back(std::abs(model::Luminance(estimate) / model::Luminance(params.rho_d) - 1));
  }
  for (int c = 0; c < 3; ++c) {
    const double bias = mean[c] / params.rho_d[c] - 1, bias_minimum = mean_minimum[c] / params.rho_d[c] - 1;
    std::printf("channel %d: bias of the floor estimate %+.4f, of the minimum %+.4f\n", c, bias, bias_minimum);
    EXPECT_LT(std::abs(bias), 0.02) << c;
    EXPECT_LT(bias_minimum, -0.05) << c;  // what the paper's eq. 14 does with these samples
  }
  std::printf("median |rho_d / true - 1| of one texel: %.4f\n", common::Median(errors));
  EXPECT_LT(common::Median(errors), 0.02);
}

// EstimateDiffuse as docs/slice-store.md states it, iterated plainly: every quantity recomputed
// at every step, at most 50 steps. `cycled` says whether it ended alternating between two sets.
struct PlainEstimate {
  DiffuseEstimate estimate;
  bool cycled = false;
};
PlainEstimate PlainDiffuseEstimate(const std::vector<model::Rgb>& r, const std::vector<double>& noise_scale,
                                   const std::vector<std::array<int, 2>>& neighbours, double clip = 2.5) {
  const size_t n = r.size();
  std::vector<double> y(n), s(n);
  for (size_t q = 0; q < n; ++q) y[q] = model::Luminance(r[q]), s[q] = std::max(noise_scale[q], 1e-300);
  const auto noise_constant = [&](const std::vector<uint8_t>& set) {
    std::vector<double> all, inner;
    for (size_t q = 0; q < n; ++q) {
      const int a = neighbours[q][0], b = neighbours[q][1];
      if (!set[q] || a < 0 || b < 0) continue;
      const double variance = s[q] * std::abs(y[q]) + 0.25 * (s[a] * std::abs(y[a]) + s[b] * std::abs(y[b]));
      if (!(variance > 0)) continue;
      const double d = std::abs(y[q] - 0.5 * (y[a] + y[b])) / std::sqrt(variance);
      all.push_back(d);
      if (set[a] && set[b]) inner.push_back(d);
    }
    std::vector<double>& used = inner.size() >= 5 ? inner : all;
    if (used.empty()) return 0.0;
    std::nth_element(used.begin(), used.begin() + used.size() / 2, used.end());
    return std::pow(used[used.size() / 2] / 0.6745, 2);
  };
  const auto mean_of = [&](const std::vector<uint8_t>& set) {
    double sum = 0, weights = 0;
    for (size_t q = 0; q < n; ++q) {
      if (set[q]) sum += y[q] / s[q], weights += 1.0 / s[q];
    }
    return sum / weights;
  };
  std::vector<size_t> order(n);
  for (size_t q = 0; q < n; ++q) order[q] = q;
  const size_t start = std::min(n, std::max<size_t>(5, n / 10));
  std::partial_sort(order.begin(), order.begin() + start, order.end(), [&](size_t a, size_t b) { return y[a] < y[b]; });
  std::vector<uint8_t> set(n, 0), before;
  for (size_t k = 0; k < start; ++k) set[order[k]] = 1;
  double floor = mean_of(set), c = noise_constant(set);
  PlainEstimate plain;
  int steps = 0;
  for (; steps < 50; ++steps) {
    const double spread = std::sqrt(c * std::max(floor, 0.0));
    std::vector<uint8_t> next(n, 0);
    size_t members = 0;
    for (size_t q = 0; q < n; ++q) {
      if (std::abs(y[q] - floor) <= clip * spread * std::sqrt(s[q])) next[q] = 1, ++members;
    }
    if (members == 0 || next == set) break;
    plain.cycled = next == before;
    before = set;
    set = next;
    floor = mean_of(set);
    c = noise_constant(set);
  }
  plain.cycled = plain.cycled && steps == 50;
  model::Rgb sum = {0, 0, 0};
  double weights = 0;
  for (size_t q = 0; q < n; ++q) {
    if (!set[q]) continue;
    for (int k = 0; k < 3; ++k) sum[k] += r[q][k] / s[q];
    weights += 1.0 / s[q];
    ++plain.estimate.floor_samples;
  }
  for (int k = 0; k < 3; ++k) plain.estimate.rho_d[k] = sum[k] / weights;
  plain.estimate.spread = std::sqrt(c * std::max(floor, 0.0));
  return plain;
}

// EstimateDiffuse computes once what does not depend on the floor set and stops a two-set
// cycle early, taking the set the 50th step would leave (a fifth of the processing's time at
// paper scale went to such cycles). Its estimate is the plain iteration's to the last bit, on
// texels that converge and on texels that cycle (which this test requires among its draws).
TEST(EstimateDiffuse, EqualsThePlainIterationToTheLastBitAlsoWhenItCycles) {
  const calib::SessionCalibration calibration = testing::AnalyticCalibration(40);
  const TexelGeometry g = MakeTexelGeometry(calibration, 1, 1);
  const std::vector<std::array<int, 2>> neighbour = OppositeNeighbours(g.dots);
  NoisyCamera camera(11);
  int cycled = 0, compared = 0;
  for (double roughness : {0.05, 0.15, 0.4}) {
    for (double floor : {0.0, 0.002, 0.02}) {
      const model::GgxNdf ndf(roughness, roughness);
      const auto [truth, scale] = TrueSamplesOf(g, ndf, TexelParams({floor, floor, floor}));
      for (int trial = 0; trial < 20; ++trial) {
        const std::vector<model::Rgb> measured = camera.Measure(truth, scale);
        const DiffuseEstimate fast = EstimateDiffuse(measured, scale, neighbour);
        const PlainEstimate plain = PlainDiffuseEstimate(measured, scale, neighbour);
        cycled += plain.cycled;
        ++compared;
        EXPECT_EQ(fast.floor_samples, plain.estimate.floor_samples) << roughness << " " << floor << " " << trial;
        EXPECT_EQ(fast.spread, plain.estimate.spread) << roughness << " " << floor << " " << trial;
        for (int c = 0; c < 3; ++c) EXPECT_EQ(fast.rho_d[c], plain.estimate.rho_d[c]) << roughness << " " << floor << " " << trial;
      }
    }
  }
  std::printf("%d of %d draws ended in a two-set cycle\n", cycled, compared);
  EXPECT_GT(cycled, 0) << "no draw exercised the cycle's shortcut";
}

TEST(EstimateDiffuse, EdgeCases) {
  EXPECT_EQ(EstimateDiffuse({}, {}, {}).floor_samples, 0);
  EXPECT_THROW(EstimateDiffuse({{1, 1, 1}}, {}, {}), common::Error);
  // Identical samples: their value.
  const DiffuseEstimate same =
      EstimateDiffuse({{0.5, 0.5, 0.5}, {0.5, 0.5, 0.5}, {0.5, 0.5, 0.5}}, {1, 2, 3}, {{{-1, -1}}, {{0, 2}}, {{-1, -1}}});
  EXPECT_DOUBLE_EQ(same.rho_d[0], 0.5);
  // A floor with a bright lobe on a third of the dots: the lobe is clipped away, and the
  // differences between neighbours give the noise.
  std::vector<model::Rgb> r;
  std::vector<double> s;
  std::vector<std::array<int, 2>> next;
  std::mt19937_64 rng(5);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (int q = 0; q < 300; ++q) {
    const double lobe = q < 100 ? 10.0 * std::exp(-q / 20.0) : 0.0;
    const double v = 1.0 + lobe + 0.03 * gauss(rng);
    r.push_back({v, v, v});
    s.push_back(1.0);
    next.push_back(q > 0 && q + 1 < 300 ? std::array<int, 2>{q - 1, q + 1} : std::array<int, 2>{-1, -1});  // a row
  }
  const DiffuseEstimate floor = EstimateDiffuse(r, s, next);
  EXPECT_NEAR(floor.rho_d[0], 1.0, 0.01);
  EXPECT_NEAR(floor.spread, 0.03, 0.01);
  EXPECT_GT(floor.floor_samples, 150);
}

// A rig from first principles: the camera 1 m away at 30 degrees from the normal (on the -y
// side), the monitor 4 cm behind the 8 cm sample, a 6 x 12 grid of dots 1 cm apart that covers
// the continued view rays in y but only part of them in x; dot (2, 6) is missing (a hole).
// The view ray through x = (x, y, 0) from V continues to x + (d / V.z) (x - V) on z = -d (similar
// triangles), so a texel has a dot beneath it when that point lies in the grid's footprint.
struct ReachRig {
  static constexpr double kSample = 0.08, kDepth = 0.04, kPitch = 0.01;
  static constexpr int kCols = 6, kRows = 12, kHoleCol = 2, kHoleRow = 6;
  static constexpr double kX0 = -0.045;  // x of the first column
  model::Vec3 camera{0.0, -std::sin(model::kPi / 6), std::cos(model::kPi / 6)};
  double y0 = 0;  // y of the first row

  calib::SessionCalibration Calibration() {
    calib::SessionCalibration c = testing::AnalyticCalibration(2);
    c.sample_plane.translation = -camera;
    c.monitor.dots.clear();
    const double centre_y = kDepth * std::tan(model::kPi / 6);
    y0 = centre_y - 0.5 * (kRows - 1) * kPitch;
    for (int row = 0; row < kRows; ++row) {
      for (int col = 0; col < kCols; ++col) {
        if (col == kHoleCol && row == kHoleRow) continue;
        calib::DotPosition dot;
        dot.position = model::Vec3(kX0 + col * kPitch, y0 + row * kPitch, -kDepth);
        dot.monitor_px = {static_cast<double>(col), static_cast<double>(row)};
        c.monitor.dots.push_back(dot);
      }
    }
    return c;
  }
  Eigen::Vector2d Hit(const model::Vec3& x) const {
    const model::Vec3 m = x + (kDepth / camera.z()) * (x - camera);
    return {m.x(), m.y()};
  }
  // Expected: inside the grid's rectangle grown by half a spacing (the hit points stay well inside
  // it in y), and not in the hole: within half a cell diagonal of some dot.
  bool Expected(const model::Vec3& x, const std::vector<model::Vec3>& dots) const {
    const Eigen::Vector2d m = Hit(x);
    if (m.x() < kX0 - 0.5 * kPitch || m.x() > kX0 + (kCols - 1) * kPitch + 0.5 * kPitch) return false;
    if (m.y() < y0 - 0.5 * kPitch || m.y() > y0 + (kRows - 1) * kPitch + 0.5 * kPitch) return false;
    double nearest = 1e300;
    for (const model::Vec3& p : dots) nearest = std::min(nearest, (m - Eigen::Vector2d(p.x(), p.y())).norm());
    return nearest <= kPitch / std::sqrt(2.0);
  }
};

TEST(DotBeneath, FlagsTexelsWhoseContinuedViewRayMissesTheDots) {
  ReachRig rig;
  const calib::SessionCalibration calibration = rig.Calibration();
  const TexelGeometry g = MakeTexelGeometry(calibration, 40, 40);
  const std::vector<uint8_t> reach = TexelsWithDotBeneath(g);
  ASSERT_EQ(static_cast<int64_t>(reach.size()), g.num_texels());
  int64_t without = 0, in_hole = 0;
  for (int64_t t = 0; t < g.num_texels(); ++t) {
    const model::Vec3 x = g.TexelCentre(t);
    const Eigen::Vector2d m = rig.Hit(x);
    // Every hit point is inside the grid's y range, so only the x edges and the hole decide.
    ASSERT_GT(m.y(), rig.y0 - 0.5 * ReachRig::kPitch);
    ASSERT_LT(m.y(), rig.y0 + (ReachRig::kRows - 0.5) * ReachRig::kPitch);
    EXPECT_EQ(reach[t] != 0, rig.Expected(x, g.dots)) << "texel " << t << " hits (" << m.x() << ", " << m.y() << ")";
    without += reach[t] ? 0 : 1;
    const Eigen::Vector2d hole(ReachRig::kX0 + ReachRig::kHoleCol * ReachRig::kPitch,
                               rig.y0 + ReachRig::kHoleRow * ReachRig::kPitch);
    in_hole += (m - hole).norm() < 0.25 * ReachRig::kPitch;
  }
  // The grid spans x in [-0.05, 0.01] grown by half a spacing; the hits span 1.046 x the sample
  // (x in [-0.042, 0.042]): the texels hitting beyond x = 0.01 (about 38% of the columns) have
  // no dot beneath, and so do the few near the hole.
  EXPECT_GT(in_hole, 0);
  EXPECT_GT(without, 0.3 * g.num_texels());
  EXPECT_LT(without, 0.5 * g.num_texels());
}

TEST(DotBeneath, StoreWritesReachAndCountsItAndTheDiffuseComesFromTheNearestTexelWithADot) {
  ReachRig rig;
  const calib::SessionCalibration calibration = rig.Calibration();
  constexpr int kTexels = 16;
  const TexelGeometry g = MakeTexelGeometry(calibration, kTexels, kTexels);
  const fs::path folder = TestFolder("reach_store");
  SliceStoreInfo info;
  info.texels_x = info.texels_y = kTexels;
  info.num_dots = static_cast<int>(g.dots.size());
  info.tile_texels = 64;  // several tiles, some without any unreached texel
  SliceStoreWriter writer(folder, info, calibration);
  // rho_d grows along x, so that a wrong neighbour shows; the lobe is a GGX one.
  const auto truth_rho_d = [&](int64_t t) { return 0.01 * (1.0 + 0.05 * static_cast<double>(t % kTexels)); };
  const model::GgxNdf ndf(0.2, 0.2);
  std::vector<float> rgb(3 * g.num_texels());
  for (int q = 0; q < info.num_dots; ++q) {
    for (int64_t t = 0; t < g.num_texels(); ++t) {
      model::DualMicrofacetParams params;
      params.eta = 1.5;
      params.alpha = 0.5;
      params.k_s = {0.8, 0.8, 0.8};
      const double d = truth_rho_d(t);
      params.rho_d = {d, d, d};
      const model::Rgb r = model::EvaluateMaterial(ndf, params, g.Light(t, q), g.View(t));
      for (int c = 0; c < 3; ++c) rgb[3 * t + c] = static_cast<float>(r[c]);
    }
    writer.WriteDot(q, rgb);
  }
  SliceStoreWriter::FinishOptions finish;
  finish.progress = false;
  writer.Finish(finish);

  const std::vector<uint8_t> expected = TexelsWithDotBeneath(g);
  const int64_t expected_without = std::count(expected.begin(), expected.end(), 0);
  ASSERT_GT(expected_without, 0);
  const SliceStore store = SliceStore::Open(folder);
  const nlohmann::json manifest = nlohmann::json::parse(std::ifstream(folder / "processed.json"));
  EXPECT_EQ(manifest.at("statistics").at("texels_without_dot_beneath").get<int64_t>(), expected_without);
  EXPECT_EQ(manifest.at("files").at("reach"), "reach.exr");
  const common::FloatImage reach = common::ReadFloatImage(folder / "reach.exr");
  ASSERT_EQ(reach.channels, 1);
  std::vector<double> floor_errors;
  for (int64_t t = 0; t < g.num_texels(); ++t) {
    const int col = static_cast<int>(t % kTexels), row = static_cast<int>(t / kTexels);
    EXPECT_EQ(reach.at(col, row), expected[t] ? 1.0f : 0.0f) << t;
    EXPECT_EQ(store.reach().at(col, row), reach.at(col, row)) << t;
    if (expected[t]) {
      // Noise-free, the floor is the texel's own diffuse term where some dots see only it (this
      // small grid leaves others on the lobe's tails everywhere, where no estimate can tell, and
      // some with a floor of a few dots only, too few to measure its noise on).
      std::vector<float> samples;
      store.ReadSamples(t, &samples);
      int on_floor = 0;  // dots that see the diffuse term alone (within 0.5%)
      for (size_t q = 0; q < g.dots.size(); ++q) on_floor += samples[3 * q] < 1.005 * truth_rho_d(t);
      const double rho = store.rho_d().at(col, row, 0);
      EXPECT_GT(rho / truth_rho_d(t), 0.99) << t;
      if (on_floor >= 8) floor_errors.push_back(std::abs(rho / truth_rho_d(t) - 1));
    }
  }
  // Noise-free, the second differences see the tails' curvature instead of noise and let some
  // tails into the floor: a few texels are 2-6% high.
  ASSERT_GT(floor_errors.size(), 10u);
  std::printf("%zu texels with a floor: median |rho_d / true - 1| %.4f, worst %.4f\n", floor_errors.size(),
              common::Median(floor_errors), *std::max_element(floor_errors.begin(), floor_errors.end()));
  EXPECT_LT(common::Median(floor_errors), 0.02);
  // The unreached texels take the diffuse term of the nearest texel with a dot beneath, along
  // the row here (the hole is not on any texel centre's hit point: every such texel is at the
  // +x side): that is the last reached column of the row, never the floor of their own tails.
  for (int row = 0; row < kTexels; ++row) {
    int last_reached = -1;
    for (int col = 0; col < kTexels; ++col) {
      if (expected[row * kTexels + col]) last_reached = col;
    }
    ASSERT_GE(last_reached, 0);
    for (int col = last_reached + 1; col < kTexels; ++col) {
      EXPECT_FLOAT_EQ(store.rho_d().at(col, row, 0), store.rho_d().at(last_reached, row, 0)) << col << ", " << row;
    }
  }
  // Every version 2 store has reach.exr: a store that lost it is refused, naming the file.
  fs::remove(folder / "reach.exr");
  try {
    SliceStore::Open(folder);
    ADD_FAILURE() << "opened a store without reach.exr";
  } catch (const common::Error& e) {
    EXPECT_NE(std::string(e.what()).find("reach.exr"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace svbtdf::process
