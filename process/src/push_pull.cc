#include "svbtdf/process/push_pull.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "svbtdf/common/error.h"

namespace svbtdf::process {
namespace {

// Position of a direction (z >= 0) in the unfolded 2N x 2N cross, in cell units (continuous).
// Top face: the square [N/2, 3N/2)^2; the side faces are its arms, each N/2 deep, with the
// horizon at the outer edge of the image.
model::Vec2 UnfoldedPosition(const model::Vec3& d, int n) {
  const double half = 0.5 * n;
  const double ax = std::abs(d.x()), ay = std::abs(d.y()), az = d.z();
  if (az >= ax && az >= ay) {  // top face: (x/z, y/z) in [-1, 1]^2
    return {n + half * d.x() / az, n + half * d.y() / az};
  }
  if (ax >= ay) {  // +x or -x side: depth along the arm is 1 - z/|x|, across it y/|x|
    const double along = half + half * (1.0 - az / ax);
    return {n + std::copysign(along, d.x()), n + half * d.y() / ax};
  }
  const double along = half + half * (1.0 - az / ay);
  return {n + half * d.x() / ay, n + std::copysign(along, d.y())};
}

}  // namespace

PushPullResampler::PushPullResampler(const model::Hemicube& light_grid) : grid_(light_grid), size_(2 * light_grid.resolution()) {
  const int n = grid_.resolution();
  if ((n & (n - 1)) != 0) {
    common::ThrowInvalidInput("light hemicube resolution", "must be a power of two for push-pull, got " + std::to_string(n));
  }
  pixel_of_cell_.resize(grid_.num_cells());
  for (int c = 0; c < grid_.num_cells(); ++c) {
    const model::Vec2 p = UnfoldedPosition(grid_.CellCenter(c), n);
    const int col = std::clamp(static_cast<int>(std::floor(p.x())), 0, size_ - 1);
    const int row = std::clamp(static_cast<int>(std::floor(p.y())), 0, size_ - 1);
    pixel_of_cell_[c] = row * size_ + col;
  }
}

void PushPullResampler::Resample(const std::vector<model::Vec3>& light, const std::vector<float>& values,
                                 const std::vector<float>& weights, std::vector<float>* cell_values,
                                 std::vector<float>* cell_confidence) const {
  if (values.size() != light.size() || weights.size() != light.size()) {
    common::ThrowInvalidInput("push-pull", "light, values and weights differ in length");
  }
  // Level 0: splat every sample with the hemicube's bilinear weights into the unfolded image.
  std::vector<std::vector<float>> sum(1), weight(1);
  sum[0].assign(static_cast<size_t>(size_) * size_, 0.0f);
  weight[0].assign(static_cast<size_t>(size_) * size_, 0.0f);
  for (size_t k = 0; k < light.size(); ++k) {
    if (!(weights[k] > 0) || !std::isfinite(values[k])) continue;
    for (const auto& [cell, w] : grid_.Interpolation(model::FlipZ(light[k]))) {
      const int pixel = pixel_of_cell_[cell];
      sum[0][pixel] += static_cast<float>(w) * weights[k] * values[k];
      weight[0][pixel] += static_cast<float>(w) * weights[k];
    }
  }
  // Pull: weighted means over 2x2 blocks, weights clamped to 1 (Gortler et al. 1996, Sec. 3.4.1).
  for (int level = 0, side = size_; side > 1; ++level, side /= 2) {
    const int next = side / 2;
    std::vector<float> next_sum(static_cast<size_t>(next) * next, 0.0f), next_weight(next_sum.size(), 0.0f);
    for (int r = 0; r < next; ++r) {
      for (int c = 0; c < next; ++c) {
        float w = 0, s = 0;
        for (int dr = 0; dr < 2; ++dr) {
          for (int dc = 0; dc < 2; ++dc) {
            const size_t fine = static_cast<size_t>(2 * r + dr) * side + (2 * c + dc);
            const float fine_weight = std::min(1.0f, weight[level][fine]);
            if (fine_weight <= 0) continue;
            w += fine_weight;
            s += fine_weight * (sum[level][fine] / weight[level][fine]);
          }
        }
        next_weight[r * next + c] = w;
        next_sum[r * next + c] = s;
      }
    }
    sum.push_back(std::move(next_sum));
    weight.push_back(std::move(next_weight));
  }
  // Push: fill in from the coarser level where a cell's own weight is below 1.
  std::vector<float> coarse_value = {weight.back()[0] > 0 ? sum.back()[0] / weight.back()[0] : 0.0f};
  for (int level = static_cast<int>(sum.size()) - 2, side = 2; level >= 0; --level, side *= 2) {
    std::vector<float> value(static_cast<size_t>(side) * side);
    for (int r = 0; r < side; ++r) {
      for (int c = 0; c < side; ++c) {
        const size_t i = static_cast<size_t>(r) * side + c;
        const float w = std::min(1.0f, weight[level][i]);
        const float own = weight[level][i] > 0 ? sum[level][i] / weight[level][i] : 0.0f;
        const float from_above = coarse_value[static_cast<size_t>(r / 2) * (side / 2) + c / 2];
        value[i] = w * own + (1.0f - w) * from_above;
      }
    }
    coarse_value = std::move(value);
  }
  cell_values->resize(grid_.num_cells());
  cell_confidence->resize(grid_.num_cells());
  for (int c = 0; c < grid_.num_cells(); ++c) {
    (*cell_values)[c] = coarse_value[pixel_of_cell_[c]];
    (*cell_confidence)[c] = weight[0][pixel_of_cell_[c]];
  }
}

}  // namespace svbtdf::process
