#pragma once
// Test support: integrals over the light hemisphere (i.z < 0) for a fixed viewer, by the cell
// centres of a hemicube.
#include <cmath>

#include "svbtdf/model/hemicube.h"

namespace svbtdf::model::testing {

// The energy a function rho(i) of the light direction sends to the viewer: the integral of
// rho(i) |i.z| over the light hemisphere.
template <typename Rho>
double EnergyOverLights(const Rho& rho, int resolution) {
  const Hemicube grid(resolution);
  double energy = 0;
  for (int c = 0; c < grid.num_cells(); ++c) {
    const Vec3 i = FlipZ(grid.CellCenter(c));
    energy += rho(i) * std::abs(i.z()) * grid.CellSolidAngle(c);
  }
  return energy;
}

}  // namespace svbtdf::model::testing
