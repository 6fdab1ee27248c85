#include "svbtdf/process/diffuse_separation.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "svbtdf/common/error.h"

namespace svbtdf::process {

std::vector<std::array<int, 2>> OppositeNeighbours(const std::vector<model::Vec3>& dots) {
  std::vector<std::array<int, 2>> pairs(dots.size(), {-1, -1});
  for (size_t q = 0; q < dots.size(); ++q) {
    double nearest = std::numeric_limits<double>::infinity();
    for (size_t a = 0; a < dots.size(); ++a) {
      if (a != q) nearest = std::min(nearest, (dots[a] - dots[q]).norm());
    }
    // Among the nearest dots (there are four on a square grid), the first whose opposite exists.
    for (size_t a = 0; a < dots.size() && pairs[q][0] < 0; ++a) {
      if (a == q || (dots[a] - dots[q]).norm() > 1.05 * nearest) continue;
      const model::Vec3 mirror = 2.0 * dots[q] - dots[a];
      for (size_t b = 0; b < dots.size(); ++b) {
        if (b != q && b != a && (dots[b] - mirror).norm() < 0.25 * nearest) {
          pairs[q] = {static_cast<int>(a), static_cast<int>(b)};
          break;
        }
      }
    }
  }
  return pairs;
}

DiffuseEstimate EstimateDiffuse(const std::vector<model::Rgb>& r, const std::vector<double>& noise_scale,
                                const std::vector<std::array<int, 2>>& neighbours, double clip) {
  if (r.size() != noise_scale.size() || r.size() != neighbours.size()) {
    common::ThrowInvalidInput("EstimateDiffuse", std::to_string(r.size()) + " samples but " +
                                             std::to_string(noise_scale.size()) + " noise scales and " +
                                             std::to_string(neighbours.size()) + " neighbour pairs");
  }
  DiffuseEstimate estimate;
  const size_t n = r.size();
  if (n == 0) return estimate;
  // Everything that does not depend on the floor set is computed once: the set is iterated on
  // up to 50 times, and these square roots and divisions were most of the processing's diffuse
  // separation (docs/benchmarks.md, "process"). The expressions are those the loops used, so
  // the estimate is the same to the last bit.
  std::vector<double> y(n), scale(n), inverse_scale(n), weighted_y(n), sqrt_scale(n);
  for (size_t q = 0; q < n; ++q) {
    y[q] = model::Luminance(r[q]);
    scale[q] = std::max(noise_scale[q], 1e-300);
    inverse_scale[q] = 1.0 / scale[q];
    weighted_y[q] = y[q] / scale[q];
    sqrt_scale[q] = std::sqrt(scale[q]);
  }
  // The shot noise's constant c (Var(y_q) = c s_q E[y_q]) from the second differences across
  // neighbouring dots, y_q - (y_a + y_b) / 2, over the samples of the floor set: the lobe is smooth
  // from dot to dot (its slope cancels), the noise is not. Each sample's normalised second
  // difference is fixed (where it has one); the set only chooses which count.
  std::vector<double> second_difference(n, 0.0);
  std::vector<uint8_t> has_difference(n, 0);
  for (size_t q = 0; q < n; ++q) {
    const int a = neighbours[q][0], b = neighbours[q][1];
    if (a < 0 || b < 0 || a >= static_cast<int>(n) || b >= static_cast<int>(n)) continue;
    const double variance = scale[q] * std::abs(y[q]) + 0.25 * (scale[a] * std::abs(y[a]) + scale[b] * std::abs(y[b]));
    if (!(variance > 0)) continue;
    second_difference[q] = std::abs(y[q] - 0.5 * (y[a] + y[b])) / std::sqrt(variance);
    has_difference[q] = 1;
  }
  // Only triples wholly in the set when there are enough of them (at least 5), so that the edge
  // of the floor, where the tails begin, does not count.
  std::vector<double> work, inner;
  const auto noise_constant = [&](const std::vector<uint8_t>& set) {
    work.clear();
    inner.clear();
    for (size_t q = 0; q < n; ++q) {
      if (!set[q] || !has_difference[q]) continue;
      work.push_back(second_difference[q]);
      if (set[neighbours[q][0]] && set[neighbours[q][1]]) inner.push_back(second_difference[q]);
    }
    if (inner.size() >= 5) work.swap(inner);
    if (work.empty()) return 0.0;
    std::nth_element(work.begin(), work.begin() + work.size() / 2, work.end());
    return std::pow(work[work.size() / 2] / 0.6745, 2);  // the median of |N(0, 1)| is 0.6745
  };
  const auto mean_of = [&](const std::vector<uint8_t>& set) {
    double sum = 0, weights = 0;
    for (size_t q = 0; q < n; ++q) {
      if (set[q]) sum += weighted_y[q], weights += inverse_scale[q];  // inverse variance on the floor
    }
    return sum / weights;
  };
  // Start from the lowest tenth of the samples (at least 5): the floor is the bottom of the data.
  std::vector<size_t> order(n);
  for (size_t q = 0; q < n; ++q) order[q] = q;
  const size_t start = std::min(n, std::max<size_t>(5, n / 10));
  std::partial_sort(order.begin(), order.begin() + start, order.end(), [&](size_t a, size_t b) { return y[a] < y[b]; });
  std::vector<uint8_t> set(n, 0), next(n), before(n);
  for (size_t k = 0; k < start; ++k) set[order[k]] = 1;
  double floor = mean_of(set), c = noise_constant(set);
  double floor_before = 0, c_before = 0;  // of `before`, the set one iteration back
  constexpr int kMaxIterations = 50;
  for (int iteration = 0; iteration < kMaxIterations; ++iteration) {
    // On the floor, sd(y_q) = sqrt(c floor s_q). The next set's weighted mean is summed in the same
    // pass, without branches (its terms in mean_of's order, non-members adding 0).
    const double spread = std::sqrt(c * std::max(floor, 0.0));
    size_t members = 0;
    double sum = 0, weights = 0;
    for (size_t q = 0; q < n; ++q) {
      const bool member = std::abs(y[q] - floor) <= clip * spread * sqrt_scale[q];
      next[q] = member;
      members += member;
      sum += member ? weighted_y[q] : 0.0;
      weights += member ? inverse_scale[q] : 0.0;
    }
    if (members == 0 || next == set) break;
    // A set that comes back after two steps alternates with the one between until the last
    // iteration: which of the two that leaves is decided by parity, without the iterations
    // (4% of a paper-scale session's texels cycled so, and took a fifth of the time).
    if (iteration > 0 && next == before) {
      if ((kMaxIterations - iteration) % 2 != 0) set.swap(before), floor = floor_before, c = c_before;
      break;
    }
    before.swap(set);
    set.swap(next);
    floor_before = floor, c_before = c;
    floor = sum / weights;
    c = noise_constant(set);
  }
  model::Rgb sum = {0, 0, 0};
  double weights = 0;
  for (size_t q = 0; q < n; ++q) {
    if (!set[q]) continue;
    for (int k = 0; k < 3; ++k) sum[k] += r[q][k] / scale[q];
    weights += inverse_scale[q];
    ++estimate.floor_samples;
  }
  for (int k = 0; k < 3; ++k) estimate.rho_d[k] = sum[k] / weights;
  estimate.spread = std::sqrt(c * std::max(floor, 0.0));
  return estimate;
}


}  // namespace svbtdf::process
