#include "svbtdf/fit/ndf_error.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace svbtdf::fit {

double NdfRelativeL2(const model::Hemicube& grid, const model::Ndf& fitted, const model::Ndf& truth) {
  std::vector<double> truth_values(grid.num_cells());
  double peak = 0;
  for (int c = 0; c < grid.num_cells(); ++c) {
    truth_values[c] = truth.D(grid.CellCenter(c));
    peak = std::max(peak, truth_values[c] * grid.CellCenter(c).z());
  }
  double error = 0, norm = 0;
  for (int c = 0; c < grid.num_cells(); ++c) {
    if (truth_values[c] * grid.CellCenter(c).z() < 0.01 * peak) continue;
    error += model::Square(fitted.D(grid.CellCenter(c)) - truth_values[c]) * grid.CellSolidAngle(c);
    norm += model::Square(truth_values[c]) * grid.CellSolidAngle(c);
  }
  return norm > 0 ? std::sqrt(error / norm) : std::nan("");
}

}  // namespace svbtdf::fit
