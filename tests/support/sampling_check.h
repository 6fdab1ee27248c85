#pragma once
// Test support: chi-square goodness-of-fit checks of a sampler against the density it reports,
// binned on the cells of a hemicube: an NDF's visible normals (CheckSampler) and a BSDF's
// directions (CheckBsdf).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>
#include <vector>

#include "chi_square.h"
#include "svbtdf/model/bsdf.h"
#include "svbtdf/model/hemicube.h"
#include "svbtdf/model/ndf.h"

namespace svbtdf::model::testing {

struct SamplerCheck {
  double chi2 = 0;
  int bins = 0;
  double pdf_integral = 0;      // integral of the reported pdf over the hemisphere
  double max_weight = 0;        // largest sample weight
  double max_pdf_mismatch = 0;  // largest |pdf - VisibleNormalPdf| / pdf over the samples
  double max_weight_mismatch = 0;  // largest |weight - G1 (v.h) D / (v.z pdf)|
  bool Passes() const { return bins > 20 && chi2 < svbtdf::testing::ChiSquareBound(bins); }
};

// The integral of `density(direction)` over every cell of `grid`: sub x sub points per cell,
// weighted by |d omega/dA| (the cube of the direction's largest component) and scaled to the
// cell's solid angle.
template <typename Density>
std::vector<double> CellIntegrals(const Hemicube& grid, const Density& density, int sub = 8) {
  std::vector<double> integrals(grid.num_cells(), 0.0);
  for (int c = 0; c < grid.num_cells(); ++c) {
    double weighted = 0, face_weight = 0;
    for (int a = 0; a < sub; ++a) {
      for (int b = 0; b < sub; ++b) {
        const Vec3 d = grid.CellPoint(c, (a + 0.5) / sub, (b + 0.5) / sub);
        const double jacobian = std::pow(std::max({std::abs(d.x()), std::abs(d.y()), d.z()}), 3);
        weighted += density(d) * jacobian;
        face_weight += jacobian;
      }
    }
    integrals[c] = weighted * grid.CellSolidAngle(c) / face_weight;
  }
  return integrals;
}

inline SamplerCheck CheckSampler(const Ndf& ndf, const Vec3& v, int samples, uint64_t seed, int resolution = 16) {
  const Hemicube grid(resolution);
  std::vector<double> expected = CellIntegrals(grid, [&](const Vec3& h) { return ndf.VisibleNormalPdf(v, h); });
  SamplerCheck check;
  for (double e : expected) check.pdf_integral += e;
  std::vector<double> observed(grid.num_cells(), 0.0);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  for (int k = 0; k < samples; ++k) {
    const NormalSample s = ndf.SampleVisibleNormal(v, Vec2(u(rng), u(rng)));
    if (!(s.pdf > 0) || s.h.z() <= 0) continue;
    ++observed[grid.CellOf(s.h)];
    check.max_weight = std::max(check.max_weight, s.weight);
    check.max_pdf_mismatch = std::max(check.max_pdf_mismatch, std::abs(s.pdf - ndf.VisibleNormalPdf(v, s.h)) / s.pdf);
    const double expected_weight = ndf.G1(v, s.h) * std::max(0.0, v.dot(s.h)) * ndf.D(s.h) / (v.z() * s.pdf);
    check.max_weight_mismatch = std::max(check.max_weight_mismatch, std::abs(s.weight - expected_weight));
  }
  for (double& e : expected) e = e / check.pdf_integral * samples;
  const svbtdf::testing::ChiSquareStatistic statistic = svbtdf::testing::PooledChiSquare(observed, expected);
  check.chi2 = statistic.chi2;
  check.bins = statistic.bins;
  return check;
}

// A BSDF's Sample against its Pdf, Eval and weight (model/bsdf.h).
// Samples binned on a hemicube of |direction| (wi lies on one side of the surface only) against
// the integral of Pdf over each cell; draws that fail form one more bin, expected to hold the
// mass the pdf lacks.
struct BsdfSamplerCheck {
  double chi2 = 0;
  int bins = 0;
  double pdf_integral = 0;
  double failure_fraction = 0;
  double max_pdf_mismatch = 0;     // |sample.pdf - Pdf(wi)| / pdf
  double max_weight_mismatch = 0;  // |weight - Eval |cos| / pdf| / (that + 1e-12), any channel
  double mean_weight = 0;          // channel-mean weight, failures counted as 0: the energy
  double weight_standard_error = 0;
  // Mean + 4.5 sigma of a chi-square with bins - 1 degrees of freedom (p about 1e-5).
  bool Passes() const { return bins > 20 && chi2 < svbtdf::testing::ChiSquareBound(bins); }
};

inline Vec3 Folded(const Vec3& d) { return {d.x(), d.y(), std::abs(d.z())}; }

inline BsdfSamplerCheck CheckBsdf(const Bsdf& bsdf, const Vec3& wo, int samples, uint64_t seed) {
  const Hemicube grid(16);
  const double side = wo.z() > 0 ? -1.0 : 1.0;  // wi's side
  std::vector<double> expected =
      CellIntegrals(grid, [&](const Vec3& d) { return bsdf.Pdf(Vec3(d.x(), d.y(), side * d.z()), wo); });
  BsdfSamplerCheck check;
  for (double e : expected) check.pdf_integral += e;
  std::vector<double> observed(grid.num_cells(), 0.0);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(0, 1);
  double failures = 0, weight_sum = 0, weight_square_sum = 0;
  for (int k = 0; k < samples; ++k) {
    const double u_lobe = uniform(rng);
    const Vec2 u(uniform(rng), uniform(rng));
    const std::optional<BsdfSample> s = bsdf.Sample(wo, u_lobe, u);
    if (!s) {
      ++failures;
      continue;
    }
    EXPECT_LT(s->wi.z() * wo.z(), 0.0);
    EXPECT_NEAR(s->wi.norm(), 1.0, 1e-9);
    ++observed[grid.CellOf(Folded(s->wi))];
    check.max_pdf_mismatch = std::max(check.max_pdf_mismatch, std::abs(s->pdf - bsdf.Pdf(s->wi, wo)) / s->pdf);
    const Rgb f = bsdf.Eval(s->wi, wo);
    for (int ch = 0; ch < 3; ++ch) {
      const double want = f[ch] * std::abs(s->wi.z()) / s->pdf;
      check.max_weight_mismatch = std::max(check.max_weight_mismatch, std::abs(s->weight[ch] - want) / (want + 1e-12));
    }
    const double w = Luminance(s->weight);
    weight_sum += w;
    weight_square_sum += w * w;
  }
  check.failure_fraction = failures / samples;
  check.mean_weight = weight_sum / samples;
  check.weight_standard_error =
      std::sqrt(std::max(0.0, weight_square_sum / samples - check.mean_weight * check.mean_weight) / samples);
  for (double& e : expected) e *= samples;
  const svbtdf::testing::ChiSquareStatistic statistic =
      svbtdf::testing::PooledChiSquare(observed, expected, failures, std::max(0.0, 1.0 - check.pdf_integral) * samples);
  check.chi2 = statistic.chi2;
  check.bins = statistic.bins;
  return check;
}

}  // namespace svbtdf::model::testing
