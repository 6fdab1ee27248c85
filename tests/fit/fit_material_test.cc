// The whole-material fit (FitMaterial) on processed sessions synthesised from a known
// dual-microfacet material (tests/support/analytic_store.h): recovery of alpha and the NDF,
// held-out error with and without clustering, the single-interface baseline, resuming, errors.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <future>
#include <limits>
#include <optional>
#include <random>
#include <thread>

#include "analytic_store.h"
#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/interrupt.h"
#include "svbtdf/common/json.h"
#include "svbtdf/common/statistics.h"
#include "svbtdf/fit/fit_material.h"
#include "svbtdf/fit/material.h"
#include "svbtdf/fit/ndf_error.h"

namespace svbtdf::fit {
namespace {
namespace fs = std::filesystem;
using testing::AnalyticMaterial;

constexpr int kDots = 24;  // per side of the dot grid

// How a material compares with the analytic truth it was fitted to.
struct Scores {
  double alpha_within_0_05 = 0;  // fraction of texels
  double ndf_rel_l2_median = 0;
  double heldout_rel_rmse = 0;   // luminance of R on the held-out dots, every texel
};

// Scores the texels listed (every texel when none are).
Scores Score(const Material& material, const AnalyticMaterial& truth, const SliceStore& store,
             std::vector<int64_t> texels = {}) {
  if (texels.empty()) {
    for (int64_t t = 0; t < store.geometry().num_texels(); ++t) texels.push_back(t);
  }
  const std::vector<int> dots = material.provenance.at("holdout").at("dots").get<std::vector<int>>();
  const MaterialEvaluator evaluator(material);
  const model::Hemicube grid(material.ndf_resolution);
  const TexelGeometry& geometry = store.geometry();
  std::vector<double> ndf_errors;
  int alpha_ok = 0;
  double error = 0, norm = 0;
  for (int64_t t : texels) {
    const int x = static_cast<int>(t % truth.width), y = static_cast<int>(t / truth.width);
    const TexelBtdf fitted = evaluator.Texel(x, y);
    alpha_ok += std::abs(fitted.params().alpha - truth.Params(x, y).alpha) <= 0.05;
    ndf_errors.push_back(NdfRelativeL2(grid, fitted.ndf(), truth.Ndf(x, y)));
    const model::Vec3 o = geometry.View(t);
    for (int q : dots) {
      const model::Vec3 i = geometry.Light(t, q);
      const double expected = model::Luminance(truth.R(x, y, i, o));
      error += model::Square(model::Luminance(fitted.Evaluate(i, o)) - expected);
      norm += model::Square(expected);
    }
  }
  Scores s;
  s.alpha_within_0_05 = static_cast<double>(alpha_ok) / texels.size();
  s.ndf_rel_l2_median = common::Median(ndf_errors);
  s.heldout_rel_rmse = std::sqrt(error / norm);
  return s;
}

class FitMaterialTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("svbtdf-fitmaterial-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    common::SetInterruptRequested(false);
    fs::remove_all(dir_);
  }

  // The 16x16-texel store with 1% noise, written once per test.
  const SliceStore& Store() {
    if (!store_) {
      testing::WriteAnalyticStore(dir_ / "processed", truth_, kDots, 0.01);
      store_ = SliceStore::Open(dir_ / "processed");
    }
    return *store_;
  }

  static FitMaterialOptions Options(double representatives, double holdout = 0.1) {
    FitMaterialOptions options;
    options.representative_fraction = representatives;
    options.holdout = holdout;
    options.progress = false;
    options.threads = 2;
    return options;
  }

  AnalyticMaterial truth_;
  fs::path dir_;
  std::optional<SliceStore> store_;
};

// Issue acceptance, scored on every texel: alpha, NDF and held-out error; the held-out dots are
// recorded. A quarter of the texels are fitted (64), the rest interpolated, to keep the test under
// a minute on 2 loaded cores (fitting all 256 took 60 s and gave 92.6%, 0.075 and 0.037).
TEST_F(FitMaterialTest, RepresentativesRecoverAlphaNdfAndHeldOutDotsOnEveryTexel) {
  const Material material = FitMaterial(Store(), Options(0.25));
  const nlohmann::json& holdout = material.provenance.at("holdout");
  EXPECT_EQ(holdout.at("dots").get<std::vector<int>>(), HeldOutDots(kDots * kDots, 0.1, 1));
  EXPECT_EQ(holdout.at("fraction").get<double>(), 0.1);
  EXPECT_EQ(material.provenance.at("statistics").at("representatives").get<int>(), 64);
  EXPECT_EQ(material.provenance.at("statistics").at("failed_fits").get<int>(), 0);
  // The three stages' wall times, disjoint parts of the whole (docs/material-format.md).
  const nlohmann::json& statistics = material.provenance.at("statistics");
  double stages = 0.0;
  for (const char* stage : {"clustering_seconds", "fit_seconds", "refine_seconds"}) {
    EXPECT_GT(statistics.at(stage).get<double>(), 0.0) << stage;
    stages += statistics.at(stage).get<double>();
  }
  EXPECT_LE(stages, statistics.at("seconds").get<double>());
  const Scores s = Score(material, truth_, Store());
  std::printf("64 of 256 texels fitted: alpha within 0.05 %.3f, NDF rel. L2 median %.4f, held-out rel. RMSE %.4f, %.3f s per fit\n",
              s.alpha_within_0_05, s.ndf_rel_l2_median, s.heldout_rel_rmse,
              material.provenance["statistics"]["seconds_per_fit"].get<double>());
  EXPECT_GE(s.alpha_within_0_05, 0.9);
  EXPECT_LT(s.ndf_rel_l2_median, 0.10);
  EXPECT_LT(s.heldout_rel_rmse, 0.05);
}

// `secant_alternations` (docs/fitting.md, step 3) end to end: recorded in the material, and the
// fit meets the same acceptance as the default's, with a held-out error no worse than 5% above it.
TEST_F(FitMaterialTest, SecantAlternationsAreRecordedAndMeetTheAcceptance) {
  FitMaterialOptions secant = Options(0.25);
  secant.secant_alternations = true;
  const Material material = FitMaterial(Store(), secant);
  const Scores with = Score(material, truth_, Store()), plain = Score(FitMaterial(Store(), Options(0.25)), truth_, Store());
  std::printf("secant alternations: alpha within 0.05 %.3f (plain %.3f), NDF %.4f (%.4f), held-out %.4f (%.4f)\n",
              with.alpha_within_0_05, plain.alpha_within_0_05, with.ndf_rel_l2_median, plain.ndf_rel_l2_median,
              with.heldout_rel_rmse, plain.heldout_rel_rmse);
  EXPECT_TRUE(material.provenance.at("settings").at("secant_alternations").get<bool>());
  EXPECT_GE(with.alpha_within_0_05, 0.9);
  EXPECT_LT(with.ndf_rel_l2_median, 0.10);
  EXPECT_LT(with.heldout_rel_rmse, 1.05 * plain.heldout_rel_rmse);
}

// Rough lobes keep much of their mass near the horizon: the paper's fixed 1e-6 there pulls the
// fitted NDF down through the smoothness rows, and leaving the horizon free recovers it (measured
// 20.7% -> 11.5% NDF error, held-out error no worse).
TEST_F(FitMaterialTest, AFreeHorizonRecoversRoughLobes) {
  truth_.rough = true;
  FitMaterialOptions fixed = Options(0.25), free = Options(0.25);
  fixed.free_horizon = false;  // the paper's; free is the default
  const Scores with_fixed = Score(FitMaterial(Store(), fixed), truth_, Store());
  const Material material = FitMaterial(Store(), free);
  const Scores with_free = Score(material, truth_, Store());
  std::printf("rough lobes, NDF rel. L2 median: horizon fixed %.4f, free %.4f; held-out %.4f, %.4f\n",
              with_fixed.ndf_rel_l2_median, with_free.ndf_rel_l2_median, with_fixed.heldout_rel_rmse,
              with_free.heldout_rel_rmse);
  EXPECT_GT(with_fixed.ndf_rel_l2_median, 0.15);  // the failure this option is for
  EXPECT_LT(with_free.ndf_rel_l2_median, 0.7 * with_fixed.ndf_rel_l2_median);
  EXPECT_LT(with_free.heldout_rel_rmse, 1.1 * with_fixed.heldout_rel_rmse);
  EXPECT_TRUE(material.provenance.at("settings").at("free_horizon").get<bool>());
}

// `--internal-reflection` end to end on a slab that has the term (GGX 0.35 lobes, 6 x 6 texels,
// 16 x 16 dots, 1% noise): representatives, refinement and the written material all carry it, and
// the held-out error against the truth is below the plain fit's. The gain is small here (1.40% ->
// 1.34% on 2026-12-05; the plain fit of the same slab without the term: 1.05%): the truth's NDF is
// analytic GGX with its own G1, which the tabulated fit only approximates, and the term depends on
// D and G1 at grazing normals, where the fixed horizon holds D down (docs/validation.md).
TEST_F(FitMaterialTest, TheInternalReflectionTermIsFittedRefinedAndWrittenAsVersion4) {
  AnalyticMaterial truth{6, 6};
  truth.across = truth.along = 0.35;
  truth.internal_reflection = true;
  testing::WriteAnalyticStore(dir_ / "slab", truth, 16, 0.01);
  const SliceStore store = SliceStore::Open(dir_ / "slab");
  FitMaterialOptions plain = Options(0.25);
  plain.free_horizon = false;
  FitMaterialOptions with_term = plain;
  with_term.internal_reflection = true;
  const Material material = FitMaterial(store, with_term);
  const Scores without = Score(FitMaterial(store, plain), truth, store), with = Score(material, truth, store);
  std::printf("slab with the term: held-out without %.4f with %.4f; alpha within 0.05: %.2f, %.2f\n",
              without.heldout_rel_rmse, with.heldout_rel_rmse, without.alpha_within_0_05, with.alpha_within_0_05);
  EXPECT_TRUE(material.internal_reflection);
  EXPECT_TRUE(material.provenance.at("settings").at("internal_reflection").get<bool>());
  EXPECT_LT(with.heldout_rel_rmse, without.heldout_rel_rmse);
  EXPECT_GE(with.alpha_within_0_05, 0.9);
  WriteMaterial(dir_ / "material", material);
  EXPECT_TRUE(ReadMaterial(dir_ / "material").internal_reflection);
}

// Clustering (paper Sec. 4.3): fitting 1% of the texels (3 of 256 here, the smallest useful
// count) predicts the held-out dots within 1.2x of the error of fitting every texel, because the
// parameters vary smoothly and the affine weights interpolate them.
TEST_F(FitMaterialTest, OnePercentRepresentativesPredictHeldOutDotsNearlyAsWellAsEveryTexel) {
  FitMaterialOptions every = Options(1.0), some = Options(0.01);
  every.ndf_resolution = some.ndf_resolution = 16;  // the comparison, not the resolution, is tested here
  const Material all = FitMaterial(Store(), every);
  const Material reps = FitMaterial(Store(), some);
  EXPECT_EQ(reps.representative_texels.size(), 3u);
  const double error_all = Score(all, truth_, Store()).heldout_rel_rmse;
  const double error_reps = Score(reps, truth_, Store()).heldout_rel_rmse;
  std::printf("held-out rel. RMSE: every texel %.4f, 1%% representatives %.4f (ratio %.2f)\n", error_all, error_reps,
              error_reps / error_all);
  EXPECT_LT(error_reps, 1.2 * error_all);
}

// The interpolated texels' refinement (refine_texels.h): with the blended NDF's weights refitted
// and alpha and k_s fitted to each texel's own samples, the held-out dots (which the refinement
// never sees) are predicted better than by the plain interpolation, and better alphas come out.
// The weights still sum to 1 (refitted ones are >= 0; a texel whose refit does not improve on the
// clustering's affine weights keeps them), and the representatives keep their own fits.
// Measured: 0.1145 -> 0.0968 (0.85x), alpha within 0.05 0.49 -> 0.67.
TEST_F(FitMaterialTest, RefiningTheInterpolatedTexelsBeatsThePlainInterpolationOnHeldOutDots) {
  FitMaterialOptions plain = Options(0.01), refined = Options(0.01);
  plain.ndf_resolution = refined.ndf_resolution = 16;
  plain.refine_texels = false;
  const Material interpolated = FitMaterial(Store(), plain);
  const Material material = FitMaterial(Store(), refined);
  const Scores before = Score(interpolated, truth_, Store()), after = Score(material, truth_, Store());
  const nlohmann::json& statistics = material.provenance.at("statistics");
  std::printf("held-out rel. RMSE %.4f -> %.4f, alpha within 0.05 %.3f -> %.3f; own samples %.4f -> %.4f\n",
              before.heldout_rel_rmse, after.heldout_rel_rmse, before.alpha_within_0_05, after.alpha_within_0_05,
              statistics.at("median_relative_rmse_blended").get<double>(),
              statistics.at("median_relative_rmse_refined").get<double>());
  EXPECT_EQ(statistics.at("refined_texels").get<int>(), 256 - 3);
  EXPECT_EQ(interpolated.provenance.at("statistics").at("refined_texels").get<int>(), 0);
  EXPECT_LT(statistics.at("median_relative_rmse_refined").get<double>(),
            statistics.at("median_relative_rmse_blended").get<double>());
  EXPECT_LT(after.heldout_rel_rmse, 0.8 * before.heldout_rel_rmse);  // measured 0.65x
  EXPECT_GE(after.alpha_within_0_05, before.alpha_within_0_05);
  for (int y = 0; y < material.height; ++y) {
    for (int x = 0; x < material.width; ++x) {
      double sum = 0;
      for (int c = 0; c < material.weight_value.channels; ++c) sum += material.weight_value.at(x, y, c);
      EXPECT_NEAR(sum, 1.0, 1e-5) << x << ", " << y;
      EXPECT_GE(material.residual.at(x, y), 0.0f) << x << ", " << y;  // every texel has its own residual now
    }
  }
  // The representatives keep their NDF tables; their alpha and k_s only ever lower their residual.
  EXPECT_EQ(statistics.at("refined_representatives").get<int>(), 3);
  EXPECT_EQ(material.representative_ln_d, interpolated.representative_ln_d);
  for (const int64_t t : material.representative_texels) {
    const int x = static_cast<int>(t % material.width), y = static_cast<int>(t / material.width);
    EXPECT_LE(material.residual.at(x, y), interpolated.residual.at(x, y) + 1e-6f) << x << ", " << y;
  }
}

// Reading a whole tile and taking a texel's slice from it (the refinement's way) gives exactly the
// slice read texel by texel, in every tile and with dots left out.
TEST(SliceStoreTiles, SlicesFromATileEqualSlicesReadAlone) {
  const fs::path dir = fs::temp_directory_path() / ("svbtdf-tiles-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  testing::AnalyticMaterial truth;
  truth.width = 12;
  truth.height = 10;  // 120 texels in tiles of 50: the last tile is part empty
  testing::WriteAnalyticStore(dir, truth, 8, 0.01, 1.5, 7, /*tile_texels=*/50);
  const SliceStore store = SliceStore::Open(dir);
  std::vector<bool> use_dot(64, true);
  for (const int q : HeldOutDots(64, 0.25, 3)) use_dot[q] = false;
  std::vector<float> tile;
  for (const int64_t texel : {0, 49, 50, 77, 100, 119}) {
    store.ReadTile(texel / 50, &tile);
    for (const std::vector<bool>& dots : {std::vector<bool>{}, use_dot}) {
      const TexelSlice alone = store.MakeTexelSlice(texel, dots);
      const TexelSlice from_tile = store.MakeTexelSlice(texel, tile, dots);
      ASSERT_EQ(from_tile.light.size(), alone.light.size()) << texel;
      EXPECT_GT(alone.light.size(), 0u);
      EXPECT_EQ(from_tile.rho, alone.rho) << texel;
      EXPECT_EQ(from_tile.solid_angle, alone.solid_angle) << texel;
      EXPECT_EQ(from_tile.view, alone.view) << texel;
      for (size_t k = 0; k < alone.light.size(); ++k) EXPECT_EQ(from_tile.light[k], alone.light[k]);
    }
  }
  std::vector<float> short_tile(10);
  EXPECT_THROW(store.MakeTexelSlice(3, short_tile), common::Error);
  fs::remove_all(dir);
}

// Version 2 stores carry their geometry in processed.json: a store whose geometry is damaged, a
// version 1 store (which has none) or a manifest whose "complete" is not a boolean is refused
// with the manifest's path.
TEST(SliceStoreFormat, DamagedGeometryAndOldVersionsAreRefusedNamingTheManifest) {
  const fs::path dir = fs::temp_directory_path() / ("svbtdf-store-format-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  testing::WriteAnalyticStore(dir, AnalyticMaterial{4, 4}, 6, 0.0, 1.5);
  const fs::path manifest_path = dir / "processed.json";
  const nlohmann::json manifest = nlohmann::json::parse(common::ReadTextFile(manifest_path));
  ASSERT_EQ(SliceStore::Open(dir).geometry().dots.size(), manifest.at("geometry").at("dots").size());
  const auto open_with = [&](const nlohmann::json& changed) {
    common::WriteTextAtomically(manifest_path, changed.dump(2) + "\n");
    try {
      SliceStore::Open(dir);
    } catch (const common::Error& e) {
      return std::string(e.what());
    }
    return std::string("opened");
  };
  nlohmann::json damaged = manifest;
  damaged["geometry"]["camera_centre"] = {0.0, 1.0};
  const std::string bad_geometry = open_with(damaged);
  EXPECT_NE(bad_geometry.find(manifest_path.string()), std::string::npos) << bad_geometry;
  EXPECT_NE(bad_geometry.find("geometry"), std::string::npos) << bad_geometry;
  nlohmann::json fewer_dots = manifest;
  fewer_dots["geometry"]["dots"].erase(0);
  EXPECT_NE(open_with(fewer_dots).find(manifest_path.string()), std::string::npos);
  nlohmann::json version_1 = manifest;
  version_1["version"] = 1;
  version_1.erase("geometry");
  const std::string old = open_with(version_1);
  EXPECT_NE(old.find(manifest_path.string()), std::string::npos) << old;
  EXPECT_NE(old.find("re-run 'svbtdf process'"), std::string::npos) << old;
  // A "complete" that is not true or false (found by fuzzing: it escaped as a JSON type error).
  nlohmann::json complete_as_text = manifest;
  complete_as_text["complete"] = "yes";
  const std::string not_boolean = open_with(complete_as_text);
  EXPECT_NE(not_boolean.find(manifest_path.string()), std::string::npos) << not_boolean;
  EXPECT_NE(not_boolean.find("\"complete\""), std::string::npos) << not_boolean;
  // The flat white's noise: a store written before it has none (0, not measured); one that is not
  // three fractions is refused.
  nlohmann::json without_noise = manifest;
  without_noise.erase("white_exitance_noise");
  EXPECT_EQ(open_with(without_noise), "opened");
  EXPECT_EQ(SliceStore::Open(dir).info().white_exitance_noise, (std::array<double, 3>{0.0, 0.0, 0.0}));
  for (const nlohmann::json& bad : {nlohmann::json{0.001, 0.002}, nlohmann::json{0.001, -0.002, 0.0},
                                    nlohmann::json{0.001, 1.5, 0.0}, nlohmann::json("0.001")}) {
    nlohmann::json damaged_noise = manifest;
    damaged_noise["white_exitance_noise"] = bad;
    const std::string refused = open_with(damaged_noise);
    EXPECT_NE(refused.find(manifest_path.string()), std::string::npos) << refused;
    EXPECT_NE(refused.find("\"white_exitance_noise\""), std::string::npos) << refused;
  }
  fs::remove_all(dir);
}

// The flat white's noise recorded by the store (SliceStoreInfo::white_exitance_noise) adds in
// quadrature to the standard errors of k_s and rho_d, channel by channel, and to the predicted
// error; nothing else of the material changes, and its provenance records it.
TEST_F(FitMaterialTest, TheFlatWhitesNoiseWidensTheErrorsOfKsAndRhoDOnly) {
  const fs::path noisy = dir_ / "noisy_flat";
  testing::WriteAnalyticStore(noisy, truth_, 12, 0.01);
  FitMaterialOptions options = Options(0.05);
  options.ndf_resolution = 16;
  const Material plain = FitMaterial(SliceStore::Open(noisy), options);
  const std::array<double, 3> noise = {0.002, 0.004, 0.0};
  nlohmann::json manifest = nlohmann::json::parse(common::ReadTextFile(noisy / "processed.json"));
  manifest["white_exitance_noise"] = noise;
  common::WriteTextAtomically(noisy / "processed.json", manifest.dump(2) + "\n");
  const Material widened = FitMaterial(SliceStore::Open(noisy), options);
  const auto recorded = widened.provenance.at("statistics").at("white_exitance_noise").get<std::array<double, 3>>();
  EXPECT_EQ(recorded, noise);
  EXPECT_EQ(widened.alpha.pixels, plain.alpha.pixels);
  EXPECT_EQ(widened.k_s.pixels, plain.k_s.pixels);
  EXPECT_EQ(widened.rho_d.pixels, plain.rho_d.pixels);
  EXPECT_EQ(widened.alpha_se.pixels, plain.alpha_se.pixels);
  const double luminance_noise = std::sqrt(0.002 * 0.002 + 0.004 * 0.004) / 3.0;
  int known = 0;
  for (int y = 0; y < plain.height; ++y) {
    for (int x = 0; x < plain.width; ++x) {
      for (int c = 0; c < 3; ++c) {
        const auto expect_widened = [&](const common::FloatImage& before, const common::FloatImage& after,
                                        const common::FloatImage& value, const char* name) {
          if (before.at(x, y, c) < 0) {
            EXPECT_EQ(after.at(x, y, c), before.at(x, y, c)) << name;  // not known stays not known
            return;
          }
          ++known;
          EXPECT_NEAR(after.at(x, y, c), std::hypot(before.at(x, y, c), noise[c] * value.at(x, y, c)),
                      1e-6 * after.at(x, y, c) + 1e-12) << name << " at " << x << ", " << y << ", channel " << c;
        };
        expect_widened(plain.k_s_se, widened.k_s_se, plain.k_s, "k_s_se");
        expect_widened(plain.rho_d_se, widened.rho_d_se, plain.rho_d, "rho_d_se");
      }
      const float predicted = plain.prediction_se.at(x, y);
      EXPECT_NEAR(widened.prediction_se.at(x, y), predicted < 0 ? predicted : std::hypot(predicted, luminance_noise), 1e-6);
    }
  }
  EXPECT_GT(known, plain.width * plain.height * 3);  // k_s's everywhere, rho_d's where the floor has samples
}

// The paper's comparison: on a dual-microfacet truth, the single-interface GGX baseline predicts
// held-out dots worse than the dual-microfacet fit with the same representatives; its material
// says what it is and evaluates through the same MaterialEvaluator after a round trip on disk.
TEST_F(FitMaterialTest, GgxBaselineIsWorseThanDualOnADualTruthAndRoundTrips) {
  FitMaterialOptions dual_options = Options(0.05), ggx_options = Options(0.05);
  ggx_options.model = MaterialModel::kWalterGgx;
  const Material dual = FitMaterial(Store(), dual_options);
  const Material ggx = FitMaterial(Store(), ggx_options);
  EXPECT_EQ(ggx.model, MaterialModel::kWalterGgx);
  EXPECT_EQ(ggx.provenance["settings"]["model"], "walter-ggx");
  EXPECT_EQ(ggx.representative_texels, dual.representative_texels);  // same clustering
  // Scored where each model is its own fit (the representatives), so that the comparison is of
  // the models, not of how well their parameters interpolate.
  const std::vector<int64_t>& reps = dual.representative_texels;
  const double error_dual = Score(dual, truth_, Store(), reps).heldout_rel_rmse;
  const double error_ggx = Score(ggx, truth_, Store(), reps).heldout_rel_rmse;
  std::printf("held-out rel. RMSE at the representatives: dual %.4f, ggx baseline %.4f; every texel: dual %.4f, "
              "ggx %.4g\n", error_dual, error_ggx, Score(dual, truth_, Store()).heldout_rel_rmse,
              Score(ggx, truth_, Store()).heldout_rel_rmse);
  EXPECT_LT(error_dual, 0.05);
  EXPECT_GT(error_ggx, 3.0 * error_dual);

  WriteMaterial(dir_ / "ggx", ggx);
  const Material read = ReadMaterial(dir_ / "ggx");
  EXPECT_EQ(read.model, MaterialModel::kWalterGgx);
  EXPECT_EQ(read.baseline_alpha_x.pixels, ggx.baseline_alpha_x.pixels);
  const MaterialEvaluator before(ggx), after(read);
  const model::Vec3 o = Store().geometry().View(100), i = Store().geometry().Light(100, 300);
  EXPECT_NEAR(after.Evaluate(4, 6, i, o)[1], before.Evaluate(4, 6, i, o)[1], 1e-6 * before.Evaluate(4, 6, i, o)[1]);
  // A representative's texel holds exactly its own baseline fit (its weight on itself is 1).
  const int64_t rep = ggx.representative_texels.front();
  std::vector<bool> use_dot(kDots * kDots, true);
  for (int q : HeldOutDots(kDots * kDots, 0.1, 1)) use_dot[q] = false;
  const BaselineFitResult own = BaselineFitter(1.5).Fit(Store().MakeTexelSlice(rep, use_dot));
  const TexelBtdf texel = after.Texel(static_cast<int>(rep % 16), static_cast<int>(rep / 16));
  ASSERT_TRUE(texel.baseline().has_value());
  EXPECT_NEAR(std::max(texel.baseline()->alpha_x, texel.baseline()->alpha_y), std::max(own.alpha_x, own.alpha_y), 1e-5);
  EXPECT_NEAR(std::min(texel.baseline()->alpha_x, texel.baseline()->alpha_y), std::min(own.alpha_x, own.alpha_y), 1e-5);
  EXPECT_NEAR(texel.Evaluate(i, o)[1], own.k_s_rgb[1] * BaselineShape(own.lobe(), 1.5, i, o) + texel.params().rho_d[1],
              1e-5 * texel.Evaluate(i, o)[1] + 1e-9);
}

// `--model slab`: the same clustering, each representative's two interfaces fitted by
// SlabFitter and held whole by its cluster, written as format version 6 and read back; a reader
// refuses the slab btdf under an older version than 5, and reads a version 5 slab (before the
// longer internal paths) with none of them. The truth here is a dual-microfacet material,
// which the slab cannot hold exactly: its accuracy is measured on traced slabs
// (slab_fit_test.cc) and the Monte Carlo truth (docs/validation.md), not here.
TEST_F(FitMaterialTest, TheSlabModelIsFittedWrittenAsVersion6AndReadBack) {
  FitMaterialOptions options = Options(0.05);
  options.model = MaterialModel::kSlab;
  const Material slab = FitMaterial(Store(), options);
  EXPECT_EQ(slab.model, MaterialModel::kSlab);
  EXPECT_EQ(slab.provenance["settings"]["model"], "slab");
  const int64_t rep = slab.representative_texels.front();
  const int x = static_cast<int>(rep % 16), y = static_cast<int>(rep / 16);
  std::vector<bool> use_dot(kDots * kDots, true);
  for (int q : HeldOutDots(kDots * kDots, 0.1, 1)) use_dot[q] = false;
  const SlabFitResult own = SlabFitter(1.5).Fit(Store().MakeTexelSlice(rep, use_dot));
  const SlabInterfaces held = TexelSlab(slab, x, y);
  EXPECT_NEAR(held.entry.alpha_x, own.interfaces.entry.alpha_x, 1e-5);
  EXPECT_NEAR(held.entry.alpha_y, own.interfaces.entry.alpha_y, 1e-5);
  EXPECT_NEAR(held.exit.alpha_x, own.interfaces.exit.alpha_x, 1e-5);
  EXPECT_NEAR(held.exit.azimuth, own.interfaces.exit.azimuth, 1e-5);
  EXPECT_NEAR(held.internal_reflection, own.interfaces.internal_reflection, 1e-5);
  EXPECT_NEAR(held.longer_paths, own.interfaces.longer_paths, 1e-5);
  EXPECT_NEAR(slab.slab_exit_roughness_se.at(x, y), own.exit_roughness_se, 1e-5);
  EXPECT_GT(own.exit_roughness_se, 0.0);
  // Every texel holds its cluster's representative's interfaces.
  for (int64_t t = 0; t < 256; ++t) {
    const int r = static_cast<int>(slab.cluster.pixels[t]);
    const int64_t own_rep = slab.representative_texels[r];
    EXPECT_EQ(slab.slab_entry_alpha_x.pixels[t], slab.slab_entry_alpha_x.pixels[own_rep]);
    EXPECT_EQ(slab.slab_exit_azimuth.pixels[t], slab.slab_exit_azimuth.pixels[own_rep]);
  }
  // The slab describes the dual truth only roughly, but it is a fit of it (measured 9.2%).
  const Scores scores = Score(slab, truth_, Store(), slab.representative_texels);
  std::printf("slab on a dual-microfacet truth: held-out rel. RMSE at the representatives %.4f\n", scores.heldout_rel_rmse);
  EXPECT_LT(scores.heldout_rel_rmse, 0.2);  // measured 0.092

  WriteMaterial(dir_ / "slab", slab);
  const nlohmann::json manifest = common::ReadJsonFile(dir_ / "slab" / "material.json");
  EXPECT_EQ(manifest["version"], 6);
  EXPECT_EQ(manifest["btdf"], "slab");
  const Material read = ReadMaterial(dir_ / "slab");
  EXPECT_EQ(read.model, MaterialModel::kSlab);
  EXPECT_EQ(read.slab_exit_alpha_y.pixels, slab.slab_exit_alpha_y.pixels);
  EXPECT_EQ(read.slab_internal_reflection.pixels, slab.slab_internal_reflection.pixels);
  EXPECT_EQ(read.slab_longer_paths.pixels, slab.slab_longer_paths.pixels);
  const MaterialEvaluator before(slab), after(read);
  const model::Vec3 o = Store().geometry().View(rep), i = Store().geometry().Light(rep, 300);
  const TexelBtdf texel = after.Texel(x, y);
  ASSERT_TRUE(texel.slab().has_value());
  EXPECT_NEAR(after.Evaluate(x, y, i, o)[1], before.Evaluate(x, y, i, o)[1], 1e-6 * before.Evaluate(x, y, i, o)[1]);
  EXPECT_NEAR(texel.Evaluate(i, o)[1], texel.params().k_s[1] * SlabShape(*texel.slab(), 1.5, i, o) + texel.params().rho_d[1],
              1e-9 * texel.Evaluate(i, o)[1]);

  // A slab under version 4, and a roughness of 0, are refused naming the file.
  nlohmann::json old = manifest;
  old["version"] = 4;
  common::WriteTextAtomically(dir_ / "slab" / "material.json", old.dump(), /*overwrite=*/true);
  EXPECT_THROW(
      try { ReadMaterial(dir_ / "slab"); } catch (const common::Error& e) {
        EXPECT_NE(std::string(e.what()).find("material.json"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("version 5"), std::string::npos) << e.what();
        throw;
      },
      common::Error);
  // Version 5 (no slab_longer_paths map): read with no longer paths.
  old["version"] = 5;
  old["maps"].erase("slab_longer_paths");
  common::WriteTextAtomically(dir_ / "slab" / "material.json", old.dump(), /*overwrite=*/true);
  const Material version5 = ReadMaterial(dir_ / "slab");
  EXPECT_EQ(version5.slab_longer_paths.width, 16);
  EXPECT_EQ(*std::max_element(version5.slab_longer_paths.pixels.begin(), version5.slab_longer_paths.pixels.end()), 0.0f);
  common::WriteTextAtomically(dir_ / "slab" / "material.json", manifest.dump(), /*overwrite=*/true);
  common::FloatImage zero = slab.slab_entry_alpha_x;
  zero.pixels[3] = 0.0f;
  common::WriteFloatImage(dir_ / "slab" / "slab_entry_alpha_x.exr", zero, false, true);
  EXPECT_THROW(
      try { ReadMaterial(dir_ / "slab"); } catch (const common::Error& e) {
        EXPECT_NE(std::string(e.what()).find("slab_entry_alpha_x.exr"), std::string::npos) << e.what();
        throw;
      },
      common::Error);
}

// Waits until the checkpoint holds `lines` lines (its header and lines - 1 fits).
void WaitForLines(const fs::path& path, int lines) {
  for (int i = 0; i < 1200; ++i) {
    std::ifstream in(path);
    if (std::count(std::istreambuf_iterator<char>(in), {}, '\n') >= lines) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
  }
  FAIL() << path << " never reached " << lines << " lines";
}

// Interrupted after a few representatives, then killed in the middle of a journal line: the rerun
// skips the journalled fits and gives exactly the material of an uninterrupted fit.
TEST_F(FitMaterialTest, AnInterruptedFitResumesToTheSameMaterial) {
  FitMaterialOptions options = Options(0.05);
  options.threads = 1;
  options.checkpoint = dir_ / "fits.jsonl";
  const SliceStore& store = Store();
  auto interrupted = std::async(std::launch::async, [&] { return FitMaterial(store, options); });
  WaitForLines(options.checkpoint, 4);
  common::SetInterruptRequested(true);
  try {
    interrupted.get();
    FAIL() << "the fit was not interrupted";
  } catch (const common::Error& e) {
    EXPECT_EQ(e.kind(), common::ErrorKind::kInterrupted) << e.what();
  }
  common::SetInterruptRequested(false);
  {  // what a kill in the middle of a write leaves
    std::ofstream torn(options.checkpoint, std::ios::app);
    torn << "{\"representative\": 12, \"result\": {\"alpha\": 0.";
  }
  const Material resumed = FitMaterial(store, options);
  const int64_t resumed_fits = resumed.provenance["statistics"]["resumed_fits"].get<int64_t>();
  EXPECT_GE(resumed_fits, 3);
  EXPECT_LT(resumed_fits, static_cast<int64_t>(resumed.representative_texels.size()));
  options.checkpoint.clear();
  const Material direct = FitMaterial(store, options);
  EXPECT_EQ(resumed.representative_texels, direct.representative_texels);
  EXPECT_EQ(resumed.alpha.pixels, direct.alpha.pixels);
  EXPECT_EQ(resumed.k_s.pixels, direct.k_s.pixels);
  EXPECT_EQ(resumed.shadowing_roughness.pixels, direct.shadowing_roughness.pixels);
  EXPECT_EQ(resumed.representative_ln_d, direct.representative_ln_d);
}

template <typename F>
std::string ErrorOf(F&& f, common::ErrorKind kind) {
  try {
    f();
  } catch (const common::Error& e) {
    EXPECT_EQ(e.kind(), kind) << e.what();
    return e.what();
  }
  ADD_FAILURE() << "no error";
  return "";
}

TEST_F(FitMaterialTest, ErrorsNameTheArgumentOrFile) {
  EXPECT_NE(ErrorOf([&] { SliceStore::Open(dir_ / "missing"); }, common::ErrorKind::kInvalidInput).find("missing"), std::string::npos);
  for (double holdout : {-0.1, 0.95, std::nan("")}) {
    EXPECT_NE(ErrorOf([&] { FitMaterial(Store(), Options(0.05, holdout)); }, common::ErrorKind::kInvalidInput).find("--holdout"),
              std::string::npos);
  }
  // A store that does not know its eta needs --eta.
  testing::WriteAnalyticStore(dir_ / "no-eta", AnalyticMaterial{4, 4}, 12, 0.0, /*store_eta=*/0.0);
  const SliceStore no_eta = SliceStore::Open(dir_ / "no-eta");
  EXPECT_NE(ErrorOf([&] { FitMaterial(no_eta, Options(0.5)); }, common::ErrorKind::kInvalidInput).find("--eta"),
            std::string::npos);
  // A checkpoint of another fit (here: another model) is refused, never mixed in.
  FitMaterialOptions options = Options(0.5);
  options.eta = 1.5;
  options.checkpoint = dir_ / "fits.jsonl";
  FitMaterial(no_eta, options);
  options.model = MaterialModel::kWalterGgx;
  EXPECT_NE(ErrorOf([&] { FitMaterial(no_eta, options); }, common::ErrorKind::kInvalidInput).find("checkpoint"),
            std::string::npos);
  // The internal-reflection term: a term of the dual model, which needs the horizon fixed.
  FitMaterialOptions with_term = Options(0.5);
  with_term.eta = 1.5;
  with_term.internal_reflection = true;
  EXPECT_NE(ErrorOf([&] { FitMaterial(no_eta, with_term); }, common::ErrorKind::kInvalidInput).find("--fixed-horizon"),
            std::string::npos);
  with_term.free_horizon = false;
  with_term.model = MaterialModel::kWalterGgx;
  EXPECT_NE(ErrorOf([&] { FitMaterial(no_eta, with_term); }, common::ErrorKind::kInvalidInput).find("--internal-reflection"),
            std::string::npos);
  with_term.model = MaterialModel::kSlab;
  EXPECT_NE(ErrorOf([&] { FitMaterial(no_eta, with_term); }, common::ErrorKind::kInvalidInput).find("--model slab has none"),
            std::string::npos);
}

TEST(ParseRepresentativeFraction, TakesAllOrAFractionAndNamesTheOptionOtherwise) {
  EXPECT_EQ(ParseRepresentativeFraction("all"), 1.0);
  EXPECT_EQ(ParseRepresentativeFraction("0.05"), 0.05);
  EXPECT_EQ(ParseRepresentativeFraction("1"), 1.0);
  for (const char* bad : {"0", "2", "0.1x", "", "-0.5", "nan"}) {
    try {
      ParseRepresentativeFraction(bad, "representatives");
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const common::Error& e) {
      EXPECT_EQ(e.kind(), common::ErrorKind::kInvalidInput);
      EXPECT_EQ(e.subject(), "representatives") << e.what();
    }
  }
}

// The masked-out texels' nearest valid texel, by the linear-time distance transform: the same
// distance as comparing every pair, on grids with one source, a few, most, a column and a row.
TEST(NearestSources, FindsTheNearestSourceOfEveryTexelAsComparingEveryPairDoes) {
  std::mt19937_64 rng(7);
  const struct {
    int width, height;
    double fraction;  // of texels that are sources
  } grids[] = {{1, 1, 1.0}, {1, 17, 0.2}, {23, 1, 0.2}, {31, 19, 0.0}, {31, 19, 0.02}, {40, 40, 0.3}, {16, 45, 0.95}};
  for (const auto& g : grids) {
    const int64_t texels = int64_t{g.width} * g.height;
    std::vector<int64_t> sources;
    std::uniform_real_distribution<double> uniform(0, 1);
    for (int64_t t = 0; t < texels; ++t) {
      if (uniform(rng) < g.fraction) sources.push_back(t);
    }
    if (sources.empty()) sources.push_back(static_cast<int64_t>(rng() % texels));  // one source alone
    const std::vector<int64_t> nearest = NearestSources(g.width, g.height, sources);
    ASSERT_EQ(static_cast<int64_t>(nearest.size()), texels);
    const auto squared_distance = [&](int64_t a, int64_t b) {
      const int64_t dx = a % g.width - b % g.width, dy = a / g.width - b / g.width;
      return dx * dx + dy * dy;
    };
    for (int64_t t = 0; t < texels; ++t) {
      int64_t best = std::numeric_limits<int64_t>::max();
      for (int64_t s : sources) best = std::min(best, squared_distance(t, s));
      ASSERT_GE(nearest[t], 0);
      ASSERT_LT(nearest[t], static_cast<int64_t>(sources.size()));
      ASSERT_EQ(squared_distance(t, sources[nearest[t]]), best)
          << g.width << " x " << g.height << " grid, " << sources.size() << " sources, texel " << t;
    }
    for (size_t k = 0; k < sources.size(); ++k) EXPECT_EQ(nearest[sources[k]], static_cast<int64_t>(k));
  }
  EXPECT_THROW(NearestSources(4, 4, {}), common::Error);
  EXPECT_THROW(NearestSources(4, 4, {16}), common::Error);
  EXPECT_THROW(NearestSources(0, 4, {0}), common::Error);
}

// A representative whose fit failed borrows the fit of the nearest one that succeeded; the others
// keep their own.
TEST(LendersOfFits, AFailedFitBorrowsTheNearestSuccessfulOne) {
  std::mt19937_64 rng(11);
  const int width = 37, height = 23;
  std::vector<int64_t> reps;
  for (int64_t t = 0; t < int64_t{width} * height; t += 1 + static_cast<int64_t>(rng() % 40)) reps.push_back(t);
  std::vector<uint8_t> failed(reps.size());
  for (uint8_t& f : failed) f = rng() % 3 == 0;
  failed[0] = 0;
  const std::vector<int> lender = LendersOfFits(reps, width, height, failed);
  ASSERT_EQ(lender.size(), reps.size());
  const auto squared_distance = [&](int64_t a, int64_t b) {
    const int64_t dx = a % width - b % width, dy = a / width - b / width;
    return dx * dx + dy * dy;
  };
  for (size_t r = 0; r < reps.size(); ++r) {
    if (!failed[r]) {
      EXPECT_EQ(lender[r], static_cast<int>(r));
      continue;
    }
    int64_t best = std::numeric_limits<int64_t>::max();
    for (size_t s = 0; s < reps.size(); ++s) {
      if (!failed[s]) best = std::min(best, squared_distance(reps[r], reps[s]));
    }
    ASSERT_GE(lender[r], 0);
    EXPECT_FALSE(failed[static_cast<size_t>(lender[r])]) << r;
    EXPECT_EQ(squared_distance(reps[r], reps[static_cast<size_t>(lender[r])]), best) << r;
  }
  EXPECT_THROW(LendersOfFits({3, 5}, 4, 4, {1, 1}), common::Error);  // none succeeded
  EXPECT_THROW(LendersOfFits({3, 5}, 4, 4, {0}), common::Error);
  EXPECT_THROW(LendersOfFits({3, 16}, 4, 4, {0, 1}), common::Error);  // a failed one outside the grid
}

}  // namespace
}  // namespace svbtdf::fit
