#include "svbtdf/session/fiducials.h"

#include <algorithm>
#include <cstdint>

#include "svbtdf/common/random.h"

namespace svbtdf::session {

std::vector<std::vector<int>> GridSymmetries(int cols, int rows) {
  // (c, r) -> (c', r') for the dihedral group of the rectangle, and of the square when it is one.
  using Map = std::pair<int, int> (*)(int c, int r, int cols, int rows);
  std::vector<Map> maps = {
      [](int c, int r, int, int) { return std::pair{c, r}; },
      [](int c, int r, int cols, int) { return std::pair{cols - 1 - c, r}; },
      [](int c, int r, int, int rows) { return std::pair{c, rows - 1 - r}; },
      [](int c, int r, int cols, int rows) { return std::pair{cols - 1 - c, rows - 1 - r}; },
  };
  if (cols == rows) {
    maps.push_back([](int c, int r, int, int) { return std::pair{r, c}; });
    maps.push_back([](int c, int r, int cols, int) { return std::pair{cols - 1 - r, c}; });
    maps.push_back([](int c, int r, int, int rows) { return std::pair{r, rows - 1 - c}; });
    maps.push_back([](int c, int r, int cols, int rows) { return std::pair{cols - 1 - r, rows - 1 - c}; });
  }
  std::vector<std::vector<int>> symmetries;
  for (Map map : maps) {
    std::vector<int> g(static_cast<size_t>(cols) * rows);
    for (int r = 0; r < rows; ++r) {
      for (int c = 0; c < cols; ++c) {
        const auto [c2, r2] = map(c, r, cols, rows);
        g[r * cols + c] = r2 * cols + c2;
      }
    }
    symmetries.push_back(std::move(g));
  }
  return symmetries;
}

int SymmetryDistance(const std::vector<bool>& lit, const std::vector<int>& symmetry) {
  int distance = 0;
  for (size_t q = 0; q < lit.size(); ++q) distance += lit[q] != lit[symmetry[q]];
  return distance;
}

std::vector<int> FiducialDots(int cols, int rows) {
  const int n = cols * rows;
  const std::vector<std::vector<int>> symmetries = GridSymmetries(cols, rows);
  std::vector<bool> best;
  int best_distance = -1;
  // The first rule of the family whose pattern every symmetry changes in a quarter of the dots;
  // a small grid may allow less: then the most distinct pattern found.
  for (uint64_t rule = 0; rule < 256 && best_distance < n / 4; ++rule) {
    std::vector<bool> lit(n);
    for (int q = 0; q < n; ++q) lit[q] = (common::SplitMix64((rule << 32) | static_cast<uint64_t>(q)) >> 33) & 1;
    int distance = n;
    for (size_t s = 1; s < symmetries.size(); ++s) distance = std::min(distance, SymmetryDistance(lit, symmetries[s]));
    if (distance > best_distance) best_distance = distance, best = lit;
  }
  std::vector<int> dots;
  for (int q = 0; q < n; ++q) {
    if (best[q]) dots.push_back(q);
  }
  return dots;
}

}  // namespace svbtdf::session
