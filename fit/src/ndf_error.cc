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

double NdfWidth(const model::Hemicube& grid, const std::vector<double>& cell_d) {
  double moment = 0, mass = 0;
  for (int c = 0; c < grid.num_cells() && c < static_cast<int>(cell_d.size()); ++c) {
    const double z = grid.CellCenter(c).z();
    const double m = cell_d[c] * z * grid.CellSolidAngle(c);
    mass += m;
    moment += m * (1.0 - z * z);
  }
  return mass > 0 ? std::sqrt(std::max(0.0, moment / mass)) : std::nan("");
}

double NdfWidth(const model::Hemicube& grid, const model::Ndf& ndf) {
  std::vector<double> d(grid.num_cells());
  for (int c = 0; c < grid.num_cells(); ++c) d[c] = ndf.D(grid.CellCenter(c));
  return NdfWidth(grid, d);
}

}  // namespace svbtdf::fit
