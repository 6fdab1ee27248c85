#pragma once
// Every texel's tabulated NDF as an anisotropic GGX lobe: what glTF's roughness and
// KHR_materials_anisotropy can carry of a fitted material (docs/export.md).
//
// A texel's table is fitted where it has mass (cells whose D h.z is at least 1% of the texel's
// peak, the cells `svbtdf compare` scores, fit::NdfRelativeL2): the lobe is where the dots'
// light landed; the tails beyond are the fit's smoothness prior, not measurements, and the
// material does not record which cells its dots reached.

#include <string>
#include <vector>

#include "svbtdf/common/image_io.h"
#include "svbtdf/fit/material.h"
#include "svbtdf/model/hemicube.h"

namespace svbtdf::exporter {

// GGX roughness alpha_x along the lobe's first axis, alpha_y along its second; the first axis
// lies at `azimuth` radians from +x, in [-pi/2, pi/2) (as fit::BaselineLobe).
struct GgxLobe {
  double alpha_x = 0.2, alpha_y = 0.2, azimuth = 0.0;
};

struct LobeFit {
  GgxLobe lobe;
  // Relative L2 distance between the lobe and the table over the cells with mass, cells weighted
  // by solid angle, both normalised (the lobe's scale fitted, so this measures shape only).
  double relative_error = 0.0;
  int iterations = 0;
};

// Fits lobes to tables on one hemicube. Construction precomputes the cells' directions and
// weights; Fit is safe to call from many threads at once.
class GgxLobeFitter {
 public:
  explicit GgxLobeFitter(const model::Hemicube& grid);
  // `cell_d`: D at every cell centre of the grid, in any positive scale.
  LobeFit Fit(const std::vector<double>& cell_d) const;

 private:
  struct Cell {
    double x, y, z, solid_angle;
  };
  std::vector<Cell> cells_;
};

// Every texel's lobe and fit error, as maps of the material's size.
struct MaterialLobes {
  common::FloatImage alpha_x, alpha_y, azimuth;  // 1 channel each, GgxLobe's meaning
  common::FloatImage relative_error;             // 1 channel: LobeFit::relative_error
  bool exact = false;  // a walter-ggx material: its texels are GGX lobes already (error 0)
};

// Throws svbtdf::Error(kInvalidInput) naming `source` (the material's manifest) for a material
// whose texels no lobe fit stands for: a slab material's are two interfaces, not one NDF.
void RequireLobeFittable(const fit::Material& material, const std::string& source);

// Fits every texel of `material` on `threads` threads (<= 0: all cores), after
// RequireLobeFittable.
MaterialLobes FitMaterialLobes(const fit::Material& material, int threads, const std::string& source = "material");

// The distribution of a map's values (a fitted lobe's error): median, 90th percentile, maximum.
struct ErrorDistribution {
  double median = 0, p90 = 0, max = 0;
};
ErrorDistribution Distribution(const common::FloatImage& map);

}  // namespace svbtdf::exporter
