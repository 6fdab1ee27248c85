// report::Compare in process: a material scores perfectly against its own truth, a known
// perturbation shows in its own metric, both truth kinds are read, and bad input is named.
// CTest runs each test in its own process and each simulation takes 15-25 s, so the checks that
// share a truth are sections of one test.
#include "svbtdf/report/compare.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "material_from_truth.h"
#include "simulated_truths.h"
#include "small_material.h"
#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/simulate/montecarlo_truth.h"

namespace svbtdf::report {
namespace {
namespace fs = std::filesystem;

CompareOptions Named(const std::string& material_folder) {
  CompareOptions options;
  options.material_folder = material_folder;
  return options;
}

TEST(Compare, AgainstAnAnalyticTruth) {
  const simulate::Truth truth = simulate::ReadTruth(SimulatedTruths::TruthFolder("model"));
  ASSERT_NE(truth.parameters(), nullptr);
  const fit::Material exact = MaterialFromTruth(*truth.parameters());
  const CompareMetrics perfect = Compare(exact, truth, Named("exact"));
  {
    SCOPED_TRACE("a material built from its truth scores perfectly");
    EXPECT_EQ(perfect.truth_kind, "analytic");
    EXPECT_TRUE(perfect.truth_has_parameters);
    EXPECT_EQ(perfect.texels_compared, 1000u);  // the default subset of the 32 x 32 texels
    EXPECT_EQ(perfect.alpha_within_0_05, 1.0);
    EXPECT_LT(perfect.alpha_error_median, 1e-6);
    EXPECT_LT(perfect.rho_d_rel_error_median, 1e-6);
    // Only the tabulation of the analytic NDF on a 32x32 hemicube separates the two.
    EXPECT_LT(perfect.ndf_rel_l2_median, 0.05);
    EXPECT_LT(perfect.heldout_rel_rmse, 0.05);
    // No holdout in a hand-made material: every dot counts as held out.
    EXPECT_FALSE(perfect.holdout_recorded);
    EXPECT_EQ(perfect.heldout_dots, truth.rig().dots.size());
    EXPECT_DOUBLE_EQ(perfect.heldout_rel_rmse, perfect.all_dots_rel_rmse);
  }
  {
    SCOPED_TRACE("alpha shifted by a tenth shows in the alpha metrics only");
    fit::Material shifted = exact;
    for (float& a : shifted.alpha.pixels) a = a > 0.5f ? a - 0.1f : a + 0.1f;
    const CompareMetrics metrics = Compare(shifted, truth, Named("shifted"));
    EXPECT_EQ(metrics.alpha_within_0_05, 0.0);
    EXPECT_NEAR(metrics.alpha_error_median, 0.1, 1e-4);
    EXPECT_LT(metrics.ndf_rel_l2_median, 0.05);       // the NDFs are untouched
    EXPECT_LT(metrics.rho_d_rel_error_median, 1e-6);  // and so is rho_d
    EXPECT_GT(metrics.heldout_rel_rmse, perfect.heldout_rel_rmse + 0.01);
  }
  {
    SCOPED_TRACE("the texel subset is bounded and seeded");
    CompareOptions options = Named("m");
    options.max_texels = 40;
    const CompareMetrics first = Compare(exact, truth, options);
    EXPECT_EQ(first.texels_compared, 40u);
    EXPECT_EQ(ToJson(Compare(exact, truth, options)).dump(), ToJson(first).dump());
  }
  {
    SCOPED_TRACE("a size mismatch names the material folder");
    try {
      Compare(SmallMaterial(), truth, Named("/where/the/material/is"));
      ADD_FAILURE() << "a 3x2 material was compared with a 32x32 truth";
    } catch (const common::Error& e) {
      EXPECT_EQ(e.kind(), common::ErrorKind::kInvalidInput);
      EXPECT_EQ(e.subject(), "/where/the/material/is");
      EXPECT_NE(e.problem().find("3x2"), std::string::npos) << e.what();
    }
  }
  {
    SCOPED_TRACE("a held-out dot the rig lacks names the material folder");
    fit::Material held = exact;
    held.provenance["holdout"]["dots"] = {static_cast<int>(truth.rig().dots.size())};
    try {
      Compare(held, truth, Named("held"));
      ADD_FAILURE() << "a held-out dot outside the rig was accepted";
    } catch (const common::Error& e) {
      EXPECT_EQ(e.subject(), "held");
      EXPECT_NE(e.problem().find("held-out dot"), std::string::npos) << e.what();
    }
  }
}

// Coverage counts the texels whose truth lies within 2 standard errors: the exact material
// with a standard error of 0.01 on alpha covers all of it, alpha shifted by 0.1 none of it, and
// shifted by 0.1 with a standard error of 0.06 all of it again; a material without standard
// errors has no coverage.
TEST(Compare, CoverageOfTheStandardErrors) {
  const simulate::Truth truth = simulate::ReadTruth(SimulatedTruths::TruthFolder("model"));
  ASSERT_NE(truth.parameters(), nullptr);
  fit::Material exact = MaterialFromTruth(*truth.parameters());
  EXPECT_TRUE(std::isnan(Compare(exact, truth, Named("none")).coverage_alpha));
  const int w = exact.width, h = exact.height;
  exact.alpha_se = common::FloatImage(w, h, 1, 0.01f);
  exact.k_s_se = common::FloatImage(w, h, 3, 0.01f);
  exact.rho_d_se = common::FloatImage(w, h, 3, -1.0f);  // not known: not counted
  exact.shadowing_roughness_se = common::FloatImage(w, h, 1, 0.01f);
  exact.ndf_width = common::FloatImage(w, h, 1, -1.0f);
  exact.ndf_width_se = common::FloatImage(w, h, 1, -1.0f);
  exact.prediction_se = common::FloatImage(w, h, 1, 0.01f);
  const CompareMetrics covered = Compare(exact, truth, Named("exact"));
  EXPECT_EQ(covered.coverage_alpha, 1.0);
  EXPECT_EQ(covered.coverage_k_s, 1.0);
  EXPECT_EQ(covered.coverage_shadowing, 1.0);
  EXPECT_TRUE(std::isnan(covered.coverage_rho_d));
  EXPECT_TRUE(std::isnan(covered.coverage_ndf_width));
  fit::Material shifted = exact;
  for (float& a : shifted.alpha.pixels) a = a > 0.5f ? a - 0.1f : a + 0.1f;
  const CompareMetrics missed = Compare(shifted, truth, Named("shifted"));
  EXPECT_EQ(missed.coverage_alpha, 0.0);
  EXPECT_NEAR(missed.z_median[0], 10.0, 1e-3);
  EXPECT_EQ(missed.coverage_k_s, 1.0);
  for (float& se : shifted.alpha_se.pixels) se = 0.06f;
  EXPECT_EQ(Compare(shifted, truth, Named("wide")).coverage_alpha, 1.0);
}

TEST(Spearman, RanksNotValues) {
  EXPECT_DOUBLE_EQ(SpearmanCorrelation({1, 2, 3, 4}, {10, 200, 3000, 40000}), 1.0);
  EXPECT_DOUBLE_EQ(SpearmanCorrelation({1, 2, 3, 4}, {4, 3, 2, 1}), -1.0);
  // Ties take their mean rank: ranks (0, 1.5, 1.5, 3) against (0, 1, 2, 3).
  EXPECT_NEAR(SpearmanCorrelation({1, 2, 2, 3}, {1, 2, 3, 4}), 4.5 / std::sqrt(4.5 * 5.0), 1e-12);
  EXPECT_TRUE(std::isnan(SpearmanCorrelation({1, 2}, {1, 2})));
  EXPECT_TRUE(std::isnan(SpearmanCorrelation({1, 1, 1}, {1, 2, 3})));
}

TEST(Compare, AMonteCarloTruthHasNoAlphaOrNdfMetrics) {
  const simulate::Truth montecarlo = simulate::ReadTruth(SimulatedTruths::TruthFolder("montecarlo"));
  EXPECT_EQ(montecarlo.kind(), "montecarlo");
  EXPECT_EQ(montecarlo.parameters(), nullptr);
  ASSERT_NE(montecarlo.montecarlo(), nullptr);
  const fit::Material uniform = SmallMaterial(montecarlo.width(), montecarlo.height());
  const CompareMetrics metrics = Compare(uniform, montecarlo, Named("m"));
  EXPECT_FALSE(metrics.truth_has_parameters);
  EXPECT_TRUE(std::isnan(metrics.alpha_within_0_05));
  EXPECT_TRUE(std::isnan(metrics.alpha_error_median));
  EXPECT_TRUE(std::isnan(metrics.ndf_rel_l2_median));
  // The truth's rho_d is 0.005 to 0.015 against the material's 0.02.
  EXPECT_GT(metrics.rho_d_rel_error_median, 0.2);
  EXPECT_LT(metrics.rho_d_rel_error_median, 3.0);
  EXPECT_TRUE(std::isfinite(metrics.heldout_rel_rmse));
  // In the JSON a missing metric is null, the others numbers.
  const nlohmann::json json = ToJson(metrics);
  EXPECT_EQ(json["truth_kind"], "montecarlo");
  EXPECT_EQ(json["truth"], montecarlo.folder().string());
  EXPECT_EQ(json["material"], "m");
  for (const char* key : {"alpha_within_0_05", "alpha_error_median", "ndf_rel_l2_median"}) {
    EXPECT_TRUE(json[key].is_null()) << key;
  }
  EXPECT_TRUE(json["heldout_rel_rmse"].is_number());
  // A material without standard errors has no coverage (issue 20's four keys are null).
  EXPECT_TRUE(json["coverage_2se"]["alpha"].is_null());
  EXPECT_TRUE(json["coverage_2se"]["rho_d"].is_null());
  EXPECT_TRUE(json["heldout_rank_correlation"].is_null());
  EXPECT_TRUE(json["slab_recovery"].empty());  // a slab material's
  // The held-out error per true slab: every slab's texels, summing to those compared.
  ASSERT_EQ(json["heldout_by_truth_slab"].size(), montecarlo.montecarlo()->materials().size());
  size_t texels = 0;
  for (const CompareMetrics::TruthSlabError& e : metrics.heldout_by_truth_slab) {
    texels += e.texels;
    EXPECT_GT(e.heldout_rel_rmse, 0.0) << e.label;
  }
  EXPECT_EQ(texels, metrics.texels_compared);
  EXPECT_EQ(json.size(), 19u);
}

// A slab material (`fit --model slab`) against the Monte Carlo truth: each true slab's texels,
// their fitted interfaces against the true ones where the truth's interface is isotropic GGX
// (the fit's family), and nothing where it is not.
TEST(Compare, ASlabMaterialIsScoredOnEachTrueSlabsRoughnesses) {
  const simulate::Truth montecarlo = simulate::ReadTruth(SimulatedTruths::TruthFolder("montecarlo"));
  fit::Material slab = SmallMaterial(montecarlo.width(), montecarlo.height());
  slab.model = fit::MaterialModel::kSlab;
  const auto map = [&](float value) {
    common::FloatImage image(slab.width, slab.height, 1);
    std::fill(image.pixels.begin(), image.pixels.end(), value);
    return image;
  };
  slab.slab_entry_alpha_x = slab.slab_entry_alpha_y = map(0.31f);  // the frosted slab's 0.30 within 15%
  slab.slab_exit_alpha_x = map(0.2f);                               // its 0.12 not: sqrt(0.2 x 0.128) = 0.16
  slab.slab_exit_alpha_y = map(0.128f);
  slab.slab_entry_azimuth = map(0.0f);
  slab.slab_exit_azimuth = map(0.5f);
  slab.slab_entry_roughness_se = slab.slab_exit_roughness_se = map(0.01f);
  slab.slab_internal_reflection = map(0.0f);  // the halo is not what this test scores (and costs 8 s)
  const CompareMetrics metrics = Compare(slab, montecarlo, Named("m"));
  ASSERT_EQ(metrics.slab_recovery.size(), montecarlo.montecarlo()->materials().size());
  size_t texels = 0;
  for (const CompareMetrics::SlabRecovery& r : metrics.slab_recovery) {
    texels += r.texels;
    EXPECT_NEAR(r.entry_median, 0.31, 1e-6);
    EXPECT_NEAR(r.exit_median, 0.16, 1e-6);
    EXPECT_NEAR(r.exit_axes_median[0], 0.2, 1e-6);
    EXPECT_NEAR(r.exit_axes_median[1], 0.128, 1e-6);
    if (r.label.rfind("frosted", 0) == 0) {
      EXPECT_DOUBLE_EQ(r.true_entry, 0.30);
      EXPECT_DOUBLE_EQ(r.true_exit, 0.12);
      EXPECT_DOUBLE_EQ(r.entry_within_15, 1.0);
      EXPECT_DOUBLE_EQ(r.exit_within_15, 0.0);
    }
    if (r.label.rfind("brushed", 0) == 0) {  // anisotropic GGX at the entry (0.08 x 0.35), Beckmann at the exit
      EXPECT_NEAR(r.true_entry, std::sqrt(0.08 * 0.35), 1e-12);
      EXPECT_DOUBLE_EQ(r.true_entry_axes[0], 0.35);
      EXPECT_DOUBLE_EQ(r.true_entry_axes[1], 0.08);
      EXPECT_TRUE(std::isnan(r.true_exit) && std::isnan(r.exit_within_15));
    }
    if (r.label.rfind("skewed", 0) == 0) {  // a tilted ellipsoid at the entry: not in the family
      EXPECT_TRUE(std::isnan(r.true_entry) && std::isnan(r.entry_within_15));
      EXPECT_DOUBLE_EQ(r.true_exit, 0.20);
    }
  }
  EXPECT_EQ(texels, metrics.texels_compared);
  EXPECT_EQ(ToJson(metrics)["slab_recovery"].size(), metrics.slab_recovery.size());
}

}  // namespace
}  // namespace svbtdf::report
