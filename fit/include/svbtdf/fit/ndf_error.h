#pragma once
// How far a fitted NDF is from a true one: the metric of `svbtdf compare` and of the fit's tests.

#include <vector>

#include "svbtdf/model/hemicube.h"
#include "svbtdf/model/ndf.h"

namespace svbtdf::fit {

// Relative L2 of the normalised NDFs over the cells of `grid` where the truth's D h.z exceeds 1%
// of its largest value (where the truth has mass), cells weighted by solid angle. NaN when the
// truth has no such cell.
double NdfRelativeL2(const model::Hemicube& grid, const model::Ndf& fitted, const model::Ndf& truth);

// The width of an NDF given by its (unnormalised, non-negative) values d_c at the cells of `grid`:
// the RMS sine of the half vector's angle from the normal, sqrt(sum d_c z_c s_c^2 Omega_c /
// sum d_c z_c Omega_c), z_c the cell centre's cosine, s_c^2 = 1 - z_c^2, Omega_c its solid angle.
// It is bounded (unlike the RMS slope of GGX's tails), and for a GGX lobe of roughness a it grows
// with a (about 0.7 a for small a). NaN when the values have no mass.
double NdfWidth(const model::Hemicube& grid, const std::vector<double>& cell_d);
// The same for an NDF, evaluated at the cell centres.
double NdfWidth(const model::Hemicube& grid, const model::Ndf& ndf);

}  // namespace svbtdf::fit
