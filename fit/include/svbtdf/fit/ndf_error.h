#pragma once
// How far a fitted NDF is from a true one: the metric of `svbtdf compare` and of the fit's tests.

#include "svbtdf/model/hemicube.h"
#include "svbtdf/model/ndf.h"

namespace svbtdf::fit {

// Relative L2 of the normalised NDFs over the cells of `grid` where the truth's D h.z exceeds 1%
// of its largest value (where the truth has mass), cells weighted by solid angle. NaN when the
// truth has no such cell.
double NdfRelativeL2(const model::Hemicube& grid, const model::Ndf& fitted, const model::Ndf& truth);

}  // namespace svbtdf::fit
