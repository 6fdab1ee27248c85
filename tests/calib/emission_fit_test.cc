// Fitting the emission profile to synthetic diffuser observations: each texel with its own
// unknown scale, the angles a 45-degree rig's dots reach, 1% noise.

#include "svbtdf/calib/emission_fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "expect_error.h"

namespace svbtdf::calib {
namespace {

double Cos(double degrees) { return std::cos(degrees * std::numbers::pi / 180.0); }

template <typename Profile>
std::vector<EmissionObservation> Observe(Profile truth, double max_deg, double noise, uint32_t seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> angle(0.0, max_deg), scale(0.5, 2.0);
  std::normal_distribution<double> gauss(0.0, noise);
  std::vector<EmissionObservation> out;
  for (int t = 0; t < 300; ++t) {
    const double c = scale(random);
    for (int q = 0; q < 60; ++q) {
      EmissionObservation o;
      o.group = t;
      o.theta_deg = angle(random);
      o.value = c * truth(o.theta_deg) * (1.0 + gauss(random));
      out.push_back(o);
    }
  }
  return out;
}

TEST(FitEmissionProfile, RecoversCosNWithPerTexelScales) {
  for (double n : {2.0, 5.0}) {
    const auto truth = [n](double theta) { return std::pow(Cos(theta), n); };
    const EmissionFit fit = FitEmissionProfile(Observe(truth, 60.0, 0.01, 7));
    const EmissionProfile& p = fit.profile;
    EXPECT_EQ(p.kind, "measured");
    EXPECT_LE(p.covered_min_deg, 2.0);
    EXPECT_GE(p.covered_max_deg, 56.0);
    double worst = 0;
    for (double theta = p.covered_min_deg; theta <= p.covered_max_deg; theta += 0.25) {
      worst = std::max(worst, std::abs(p.AtDegrees(theta) / truth(theta) - 1.0));
    }
    EXPECT_LT(worst, 0.005) << "n = " << n;
    EXPECT_NEAR(p.exponent, n, 0.05);
    EXPECT_NEAR(fit.report.residual_rms, 0.01, 0.002);  // the noise, nothing more
    EXPECT_EQ(fit.report.texels, 300);
    // Each node's standard error is what its scatter says: within 3 of the truth.
    for (size_t k = 1; k < p.table.size(); ++k) {
      EXPECT_LT(std::abs(std::log(p.table[k] / truth(k * p.step_deg))), 3 * fit.report.table_std[k] + 0.003) << k;
    }
  }
}

// A profile no cos^n describes (an LCD's flattened core): the table follows it, the single cos^n
// leaves a residual several times the noise.
TEST(FitEmissionProfile, TableFollowsAShapeNoCosPowerHas) {
  const auto truth = [](double theta) { return std::pow(Cos(theta), 4.0) * (1.0 + 0.8 * std::pow(std::sin(theta * std::numbers::pi / 180.0), 2)); };
  const EmissionFit fit = FitEmissionProfile(Observe(truth, 60.0, 0.01, 3));
  for (double theta = fit.profile.covered_min_deg; theta <= fit.profile.covered_max_deg; theta += 0.25) {
    EXPECT_NEAR(fit.profile.AtDegrees(theta) / truth(theta), 1.0, 0.005) << theta;
  }
  EXPECT_GT(fit.report.cos_power_residual_rms, 2.0 * fit.report.residual_rms);
}

TEST(FitEmissionProfile, ReportsOnlyTheAnglesTheDataReach) {
  const auto truth = [](double theta) { return std::pow(Cos(theta), 3.0); };
  std::vector<EmissionObservation> obs = Observe([&](double theta) { return truth(theta + 10.0); }, 30.0, 0.01, 5);
  for (EmissionObservation& o : obs) o.theta_deg += 10.0;  // 10 to 40 degrees
  const EmissionFit fit = FitEmissionProfile(obs);
  EXPECT_GE(fit.profile.covered_min_deg, 8.0);
  EXPECT_LE(fit.profile.covered_max_deg, 40.0);
  EXPECT_GE(fit.profile.covered_max_deg, 36.0);
  EXPECT_EQ(fit.profile.table.front(), 1.0);  // the scale: P(0) = 1, extrapolated
  // Shape within the covered angles, up to the scale (P(0) is not observed).
  const double scale = fit.profile.AtDegrees(20.0) / truth(20.0);
  for (double theta = fit.profile.covered_min_deg; theta <= fit.profile.covered_max_deg; theta += 0.5) {
    EXPECT_NEAR(fit.profile.AtDegrees(theta) / (scale * truth(theta)), 1.0, 0.005) << theta;
  }
}

TEST(FitEmissionProfile, RefusesDataAtOneAngle) {
  std::vector<EmissionObservation> obs;
  for (int t = 0; t < 10; ++t) obs.push_back({t, 0.0, 1.0, 1.0});
  testing::ExpectError(common::ErrorKind::kInvalidInput, "covers fewer than two angles", [&] { FitEmissionProfile(obs); });
  testing::ExpectError(common::ErrorKind::kInvalidInput, "no positive measurement",
                       [&] { FitEmissionProfile({{0, 10.0, -1.0, 1.0}}); });
}

}  // namespace
}  // namespace svbtdf::calib
