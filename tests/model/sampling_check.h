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

inline SamplerCheck CheckSampler(const Ndf& ndf, const Vec3& v, int samples, uint64_t seed, int resolution = 16) {
  const Hemicube grid(resolution);
  constexpr int kSub = 8;
  std::vector<double> expected(grid.num_cells(), 0.0);
  SamplerCheck check;
  for (int c = 0; c < grid.num_cells(); ++c) {
    double weighted = 0, face_weight = 0;
    for (int a = 0; a < kSub; ++a) {
      for (int b = 0; b < kSub; ++b) {
        const Vec3 h = grid.CellPoint(c, (a + 0.5) / kSub, (b + 0.5) / kSub);
        const double jacobian = std::pow(std::max({std::abs(h.x()), std::abs(h.y()), h.z()}), 3);
        weighted += ndf.VisibleNormalPdf(v, h) * jacobian;
        face_weight += jacobian;
      }
    }
    expected[c] = weighted * grid.CellSolidAngle(c) / face_weight;
    check.pdf_integral += expected[c];
  }
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
  double pooled_observed = 0, pooled_expected = 0;
  for (int c = 0; c < grid.num_cells(); ++c) {
    const double e = expected[c] / check.pdf_integral * samples;
    if (e < 20) {
      pooled_observed += observed[c];
      pooled_expected += e;
      continue;
    }
    check.chi2 += (observed[c] - e) * (observed[c] - e) / e;
    ++check.bins;
  }
  if (pooled_expected > 20) {
    check.chi2 += (pooled_observed - pooled_expected) * (pooled_observed - pooled_expected) / pooled_expected;
    ++check.bins;
  }
  return check;
}

}  // namespace svbtdf::model::testing
