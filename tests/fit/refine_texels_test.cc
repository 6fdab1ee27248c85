// RefineTexels (fit/src/refine_texels.cc) on a store synthesised from a known material
// (tests/support/analytic_store.h): starting from a material whose alpha and k_s are off, the
// refinement brings them back to the truth, lowers (never raises) every texel's residual on its
// own samples and writes that residual; it honours an interrupt and refuses a store of another
// size.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <vector>

#include "analytic_store.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/interrupt.h"
#include "svbtdf/fit/material.h"
#include "svbtdf/fit/refine_texels.h"
#include "svbtdf/fit/slice_store.h"
#include "svbtdf/model/tabulated_ndf.h"
#include "temp_folder.h"

namespace svbtdf::fit {
namespace {
namespace fs = std::filesystem;

constexpr int kSide = 4;          // 4 x 4 texels
constexpr int kDots = 16;         // 16 x 16 dots
constexpr int kNdfResolution = 32;

// The truth's material with every texel of columns 0 and 3 a representative holding its own true
// NDF (tabulated), and the texels of columns 1 and 2 blends of the two representatives of their
// row; alpha and k_s are the truth's, moved by `alpha_offset` (alternating in sign, clamped to
// [0, 1]) and scaled by `k_s_factor`.
Material PerturbedMaterial(const testing::AnalyticMaterial& truth, double alpha_offset, double k_s_factor) {
  Material m;
  m.width = truth.width;
  m.height = truth.height;
  m.eta = truth.eta;
  m.ndf_resolution = kNdfResolution;
  m.alpha = common::FloatImage(m.width, m.height, 1, 0.0f);
  m.shadowing_roughness = common::FloatImage(m.width, m.height, 1, 0.2f);  // the truth's SmithShadowing::Ggx(0.2)
  m.k_s = common::FloatImage(m.width, m.height, 3, 0.0f);
  m.rho_d = common::FloatImage(m.width, m.height, 3, 0.0f);
  m.residual = common::FloatImage(m.width, m.height, 1, -1.0f);
  m.cluster = common::FloatImage(m.width, m.height, 1, 0.0f);
  m.weight_index = common::FloatImage(m.width, m.height, 2, 0.0f);
  m.weight_value = common::FloatImage(m.width, m.height, 2, 0.0f);
  const model::Hemicube grid(kNdfResolution);
  for (int y = 0; y < m.height; ++y) {
    for (int x : {0, m.width - 1}) {
      model::TabulatedNdf ndf(grid, truth.Ndf(x, y));
      ndf.Normalize();
      m.representative_texels.push_back(static_cast<int64_t>(y) * m.width + x);
      m.representative_ln_d.push_back(ndf.ln_d());
    }
  }
  for (int y = 0; y < m.height; ++y) {
    for (int x = 0; x < m.width; ++x) {
      const model::DualMicrofacetParams p = truth.Params(x, y);
      const double sign = (x + y) % 2 == 0 ? 1.0 : -1.0;
      m.alpha.at(x, y) = static_cast<float>(std::clamp(p.alpha + sign * alpha_offset, 0.0, 1.0));
      for (int c = 0; c < 3; ++c) m.k_s.at(x, y, c) = static_cast<float>(k_s_factor * p.k_s[c]);
      const int left = 2 * y, right = 2 * y + 1;  // this row's representatives
      const double u = x / (m.width - 1.0);
      m.weight_index.at(x, y, 0) = static_cast<float>(left);
      m.weight_index.at(x, y, 1) = static_cast<float>(right);
      m.weight_value.at(x, y, 0) = static_cast<float>(1.0 - u);
      m.weight_value.at(x, y, 1) = static_cast<float>(u);
      m.cluster.at(x, y) = static_cast<float>(u < 0.5 ? left : right);
    }
  }
  return m;
}

// `material` with standard-error maps (all 0, as an assembly without profile errors would leave
// them), so that the refinement writes its own.
Material WithStandardErrorMaps(Material material) {
  const int w = material.width, h = material.height;
  for (common::FloatImage* map : {&material.alpha_se, &material.shadowing_roughness_se, &material.ndf_width_se,
                                  &material.ndf_width, &material.prediction_se}) {
    *map = common::FloatImage(w, h, 1, 0.0f);
  }
  material.k_s_se = common::FloatImage(w, h, 3, 0.0f);
  material.rho_d_se = common::FloatImage(w, h, 3, 0.0f);
  return material;
}

// A texel's relative RMSE on its own luminance samples, computed here from the evaluator (not
// from what RefineTexels reports).
double RelativeRmse(const Material& material, const SliceStore& store, int64_t t) {
  const TexelSlice slice = store.MakeTexelSlice(t);
  const TexelBtdf texel = MaterialEvaluator(material).Texel(static_cast<int>(t % material.width),
                                                            static_cast<int>(t / material.width));
  double error = 0, norm = 0;
  for (size_t k = 0; k < slice.light.size(); ++k) {
    const double r = model::Luminance(texel.Evaluate(slice.light[k], slice.view));
    error += (r - slice.rho[k]) * (r - slice.rho[k]);
    norm += slice.rho[k] * slice.rho[k];
  }
  return std::sqrt(error / norm);
}

bool IsRepresentative(const Material& m, int64_t t) {
  return std::find(m.representative_texels.begin(), m.representative_texels.end(), t) != m.representative_texels.end();
}

class RefineTexelsTest : public ::testing::Test {
 protected:
  // One store for the suite (noise 0.5%): written once, read by every test.
  static void SetUpTestSuite() {
    folder_ = std::make_unique<svbtdf::testing::TempFolder>("refine-texels");
    truth_.width = truth_.height = kSide;
    svbtdf::testing::WriteAnalyticStore(folder_->path() / "processed", truth_, kDots, 0.005);
    store_ = std::make_unique<SliceStore>(SliceStore::Open(folder_->path() / "processed"));
  }
  static void TearDownTestSuite() {
    store_.reset();
    folder_.reset();
  }
  void TearDown() override { common::SetInterruptRequested(false); }

  static std::vector<int64_t> AllTexels() {
    std::vector<int64_t> texels(kSide * kSide);
    std::iota(texels.begin(), texels.end(), 0);
    return texels;
  }
  static RefineOptions Options() {
    RefineOptions options;
    options.threads = 2;
    return options;
  }

  static inline std::unique_ptr<svbtdf::testing::TempFolder> folder_;
  static inline testing::AnalyticMaterial truth_;
  static inline std::unique_ptr<SliceStore> store_;
};

TEST_F(RefineTexelsTest, BringsAlphaAndKsBackToTheTruthAndLowersEveryResidual) {
  Material material = PerturbedMaterial(truth_, 0.25, 1.3);
  std::vector<double> before;
  for (int64_t t : AllTexels()) before.push_back(RelativeRmse(material, *store_, t));
  const RefineStatistics statistics = RefineTexels(*store_, {}, AllTexels(), Options(), &material);
  EXPECT_EQ(statistics.representatives, 2 * kSide);
  EXPECT_EQ(statistics.texels, kSide * kSide - 2 * kSide);
  EXPECT_LT(statistics.median_rmse_refined, statistics.median_rmse_blended);

  for (int64_t t : AllTexels()) {
    const int x = static_cast<int>(t % kSide), y = static_cast<int>(t / kSide);
    const model::DualMicrofacetParams p = truth_.Params(x, y);
    const double after = RelativeRmse(material, *store_, t);
    // Never worse, and the residual written is the one a reader of the material measures.
    EXPECT_LE(after, before[t] * (1 + 1e-6)) << "texel " << t;
    EXPECT_NEAR(material.residual.at(x, y), after, 1e-3) << "texel " << t;
    // The representatives hold the true NDF (tabulated at 32): alpha and k_s come back from 0.25
    // and 30% off to within what the noise (0.5%) and the tabulation allow (measured: alpha within
    // 0.031, k_s within 2.5%, residual 0.9-1.5%). The blended texels' NDF is a blend of their
    // row's two, close to theirs but not equal (measured: alpha within 0.035, k_s 3.3%, residual
    // about 2%).
    const double alpha_error = std::abs(material.alpha.at(x, y) - p.alpha);
    const double k_s_error = std::abs(material.k_s.at(x, y, 0) / p.k_s[0] - 1.0);
    std::printf("texel %2lld %s: residual %.4f -> %.4f, alpha %.3f (truth %.3f), k_s/truth %.3f\n",
                static_cast<long long>(t), IsRepresentative(material, t) ? "rep  " : "blend", before[t], after,
                material.alpha.at(x, y), p.alpha, material.k_s.at(x, y, 0) / p.k_s[0]);
    if (IsRepresentative(material, t)) {
      EXPECT_LT(after, 0.02) << "texel " << t;
      EXPECT_LT(alpha_error, 0.05) << "texel " << t;
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(material.k_s.at(x, y, c) / p.k_s[c], 1.0, 0.04) << "texel " << t;
    } else {
      EXPECT_LT(after, 0.03) << "texel " << t;
      EXPECT_LT(alpha_error, 0.06) << "texel " << t;
      EXPECT_LT(k_s_error, 0.05) << "texel " << t;
    }
  }
}

// Without alpha (the baseline's mode) only the blended texels' k_s moves, back toward the truth;
// alpha is left exactly as it was and the representatives are not touched.
TEST_F(RefineTexelsTest, KsOnlyLeavesAlphaAndTheRepresentativesAsTheyWere) {
  const Material start = PerturbedMaterial(truth_, 0.0, 0.7);
  Material material = start;
  RefineOptions options = Options();
  options.refine_alpha = false;
  options.refit_weights = false;
  const RefineStatistics statistics = RefineTexels(*store_, {}, AllTexels(), options, &material);
  EXPECT_EQ(statistics.representatives, 0);
  EXPECT_EQ(material.alpha.pixels, start.alpha.pixels);
  for (int64_t t : AllTexels()) {
    const int x = static_cast<int>(t % kSide), y = static_cast<int>(t / kSide);
    const model::DualMicrofacetParams p = truth_.Params(x, y);
    for (int c = 0; c < 3; ++c) {
      if (IsRepresentative(material, t)) {
        EXPECT_EQ(material.k_s.at(x, y, c), start.k_s.at(x, y, c)) << "texel " << t;
      } else {
        EXPECT_NEAR(material.k_s.at(x, y, c) / p.k_s[c], 1.0, 0.1) << "texel " << t;  // started 30% off
      }
    }
  }
}

// Only the texels asked for change.
TEST_F(RefineTexelsTest, LeavesTheOtherTexelsAlone) {
  const Material start = PerturbedMaterial(truth_, 0.25, 1.3);
  Material material = start;
  const int64_t chosen = 1 * kSide + 2;  // a blended texel
  RefineTexels(*store_, {}, {chosen}, Options(), &material);
  for (int64_t t : AllTexels()) {
    const int x = static_cast<int>(t % kSide), y = static_cast<int>(t / kSide);
    if (t == chosen) {
      EXPECT_NE(material.alpha.at(x, y), start.alpha.at(x, y));
      continue;
    }
    EXPECT_EQ(material.alpha.at(x, y), start.alpha.at(x, y)) << "texel " << t;
    EXPECT_EQ(material.k_s.at(x, y, 0), start.k_s.at(x, y, 0)) << "texel " << t;
    EXPECT_EQ(material.residual.at(x, y), -1.0f) << "texel " << t;
  }
}

// The model error (StandardErrorOptions) only widens the texels' statistical errors. Pooled
// over 3 x 3 texels (the default) it reaches the representatives, which are fitted once; with
// each texel's own draw (radius 0) it leaves them as they were.
TEST_F(RefineTexelsTest, TheModelErrorWidensTheErrorsAndItsPoolingIsAnOption) {
  const auto refined = [](const StandardErrorOptions& standard_errors) {
    Material material = WithStandardErrorMaps(PerturbedMaterial(truth_, 0.25, 1.3));
    RefineOptions options = Options();
    options.standard_errors = standard_errors;
    RefineTexels(*store_, {}, AllTexels(), options, &material);
    return material;
  };
  StandardErrorOptions without_model_error, own_draw;
  without_model_error.model_error = false;
  own_draw.model_error_pool_radius = 0;
  const Material statistical = refined(without_model_error), pooled = refined({}), unpooled = refined(own_draw);
  int widened_representatives = 0, widened_blends = 0;
  for (int64_t t : AllTexels()) {
    const float base = statistical.alpha_se.pixels[t];
    ASSERT_GT(base, 0.0f) << "texel " << t;
    EXPECT_GE(pooled.alpha_se.pixels[t], base) << "texel " << t;
    EXPECT_GE(unpooled.alpha_se.pixels[t], base) << "texel " << t;
    if (IsRepresentative(pooled, t)) {
      EXPECT_EQ(unpooled.alpha_se.pixels[t], base) << "texel " << t;
      widened_representatives += pooled.alpha_se.pixels[t] > base;
    } else {
      widened_blends += unpooled.alpha_se.pixels[t] > base;
    }
  }
  EXPECT_GT(widened_representatives, 0);
  EXPECT_GT(widened_blends, 0);
}

TEST_F(RefineTexelsTest, AnInterruptStopsItWithAnInterruptedError) {
  Material material = PerturbedMaterial(truth_, 0.25, 1.3);
  common::SetInterruptRequested(true);
  try {
    RefineTexels(*store_, {}, AllTexels(), Options(), &material);
    FAIL() << "the interrupt was not honoured";
  } catch (const common::Error& e) {
    EXPECT_EQ(e.kind(), common::ErrorKind::kInterrupted);
  }
  common::SetInterruptRequested(false);
  EXPECT_NO_THROW(RefineTexels(*store_, {}, AllTexels(), Options(), &material));
}

TEST_F(RefineTexelsTest, RefusesAStoreOfAnotherSizeAndTexelsOutsideTheMaterial) {
  testing::AnalyticMaterial other = truth_;
  other.width = kSide + 1;
  Material material = PerturbedMaterial(other, 0.0, 1.0);
  try {
    RefineTexels(*store_, {}, {0}, Options(), &material);
    FAIL() << "a material of another size was refined";
  } catch (const common::Error& e) {
    EXPECT_EQ(e.kind(), common::ErrorKind::kInvalidInput);
  }
  Material right = PerturbedMaterial(truth_, 0.0, 1.0);
  try {
    RefineTexels(*store_, {}, {kSide * kSide}, Options(), &right);
    FAIL() << "a texel outside the material was refined";
  } catch (const common::Error& e) {
    EXPECT_EQ(e.kind(), common::ErrorKind::kInvalidInput);
  }
}

}  // namespace
}  // namespace svbtdf::fit
