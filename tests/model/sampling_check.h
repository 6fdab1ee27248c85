#pragma once
// Test support: a chi-square goodness-of-fit check of an NDF's visible-normal sampler against the
// density it reports, binned on the cells of a hemicube.
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

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
  // p < 1e-4 for a chi-square with bins - 1 degrees of freedom is about mean + 4.5 sigma.
  bool Passes() const { return bins > 20 && chi2 < (bins - 1) + 4.5 * std::sqrt(2.0 * (bins - 1)); }
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

struct ChiSquareStatistic {
  double chi2 = 0;
  int bins = 0;
};

// Pearson's chi-square of observed against expected counts. Bins expected to hold fewer than 20
// are pooled into one bin, which starts with `pooled_observed` and `pooled_expected` (a mass
// that has no cell, such as the draws a sampler failed).
inline ChiSquareStatistic PooledChiSquare(const std::vector<double>& observed, const std::vector<double>& expected,
                                          double pooled_observed = 0, double pooled_expected = 0) {
  ChiSquareStatistic result;
  for (size_t c = 0; c < observed.size(); ++c) {
    const double e = expected[c];
    if (e < 20) {
      pooled_observed += observed[c];
      pooled_expected += e;
      continue;
    }
    result.chi2 += (observed[c] - e) * (observed[c] - e) / e;
    ++result.bins;
  }
  if (pooled_expected > 20) {
    result.chi2 += (pooled_observed - pooled_expected) * (pooled_observed - pooled_expected) / pooled_expected;
    ++result.bins;
  }
  return result;
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
  const ChiSquareStatistic statistic = PooledChiSquare(observed, expected);
  check.chi2 = statistic.chi2;
  check.bins = statistic.bins;
  return check;
}

}  // namespace svbtdf::model::testing
