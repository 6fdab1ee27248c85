#pragma once
// Validation of the dual-microfacet model against the Monte Carlo slab (the paper's Figs. 3 and 5;
// docs/validation.md). For a slab whose interfaces share one NDF (rough entry only, rough exit only,
// or both rough) and a fixed view direction, it compares the MC slice over the light hemicube with
// the model's rho_T, rho_B, their best log-space blend, and Walter's single-interface BTDF (with the
// same NDF, and with its roughness fitted to the MC slice).
//
// Every model is averaged over each hemicube cell exactly as the MC estimates cell averages, so
// that binning does not count as model error. Errors are relative L2 norms over the whole slice
// with cells weighted by their solid angle:
//     error(m) = sqrt( sum_c Omega_c (m_c - mc_c)^2 / sum_c Omega_c mc_c^2 ).

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "svbtdf/model/internal_reflection.h"
#include "svbtdf/model/ndf.h"
#include "svbtdf/model/slab_transmission.h"
#include "svbtdf/model/vec.h"
#include "svbtdf/simulate/slab_tracer.h"

namespace svbtdf::simulate {

// The model terms evaluated with the NDF's own Smith G1 in place of the model's shadowing term
// (the same masking the MC tracer applies), so that a comparison isolates the virtual
// configurations. rho_T = factor_T D(h_T) G1(i, h_T) G1(t, h_T) with t the in-slab direction;
// rho_B = factor_B D(h_B) G1(t_i, h_B) G1(o, h_B) (docs/model.md).
double RhoTWithNdfShadowing(const model::Ndf& ndf, double eta, const model::Vec3& i, const model::Vec3& o);
double RhoBWithNdfShadowing(const model::Ndf& ndf, double eta, const model::Vec3& i, const model::Vec3& o);

// The paper's single-refraction ("GGX", Walter et al. 2007) baseline: one rough interface from air
// into the slab, with the camera direction o taken as the refracted direction:
// WalterBtdf(ndf, i, o, 1, eta). See docs/validation.md for why this reading.
double SingleInterfaceBtdf(const model::Ndf& ndf, double eta, const model::Vec3& i, const model::Vec3& o);

// Cell averages, over a hemicube of light directions, of functions of the light direction i.
// Each cell is split into k x k sub-cells whose solid angles weight the values at their centres.
class CellAverager {
 public:
  // `grid` must outlive the averager.
  CellAverager(const model::Hemicube& grid, int subdivisions);

  const model::Hemicube& grid() const { return grid_; }
  int num_points() const { return static_cast<int>(directions_.size()); }
  // Light directions (z < 0) of the sub-cell centres, cell by cell.
  const std::vector<model::Vec3>& light_directions() const { return directions_; }
  // Averages point values (in light_directions() order) over each cell.
  std::vector<double> Average(const std::vector<double>& point_values) const;
  // Evaluates f at every point and averages.
  std::vector<double> Average(const std::function<double(const model::Vec3& i)>& f) const;

 private:
  const model::Hemicube& grid_;
  int per_cell_;
  std::vector<model::Vec3> directions_;
  std::vector<double> weights_;  // sub-cell solid angle / cell solid angle
};

// Relative L2 distance of `model` from `reference` over the cells, weighted by solid angle.
double RelativeL2Error(const std::vector<double>& predicted, const std::vector<double>& reference,
                       const std::vector<double>& solid_angles);

enum class RoughSides { kEntry, kExit, kBoth };
const char* ToString(RoughSides sides);  // "entry", "exit", "both"

struct ModelErrors {
  double rho_T = 0.0;
  double rho_B = 0.0;
  double blend = 0.0;
  double single_same_ndf = 0.0;
  double single_fitted = 0.0;
  // Not in the paper: the blend with its NDF roughness fitted as well (alongside alpha), the fair
  // counterpart of single_fitted.
  double blend_fitted = 0.0;
  // Seed 000's analytic slab lobe (model/slab_lobe.h) with each rough interface's NDF matched by a
  // vMF of the same mean cosine (MatchedVmfConcentration).
  double slab_lobe = 0.0;
  // The best-alpha blend plus the internal-reflection term (T R R T paths, same NDF, blended with
  // the same alpha), alpha refitted; and the same with the NDF roughness fitted too.
  double blend_internal = 0.0;
  double blend_internal_fitted = 0.0;
  // The exact transmission of the slab's two interfaces without internal reflection
  // (model/slab_transmission.h; a flat side is the NDF at roughness 5e-4), and the same plus the
  // internal reflection's shape at its least-squares weight (what `svbtdf fit --model slab`
  // fits): the rough side's T R R T term for one rough side, SlabInternalReflection for both.
  double two_interfaces = 0.0;
  double two_interfaces_internal = 0.0;
  // The same plus a second shape for the longer internal paths (T (R R)^n T, n >= 2), whose halo
  // is wider: the internal reflection's shape with each rough side's NDF widened by
  // `ValidationOptions::longer_paths_widening`; both shapes' weights fitted (>= 0).
  double two_interfaces_internal_longer = 0.0;
};

// Relative L2 error of s * model after the best scale s > 0: what remains once the overall
// transmitted energy is discounted, i.e. the error in the lobe's shape and position.
double ScaleFreeRelativeL2Error(const std::vector<double>& predicted, const std::vector<double>& reference,
                                const std::vector<double>& solid_angles);

struct ValidationCase {
  RoughSides rough_sides = RoughSides::kBoth;
  double incidence_deg = 0.0;  // polar angle of the fixed view direction o = (sin, 0, cos)
  model::Vec3 o = model::Vec3::UnitZ();
  double best_alpha = 0.5;        // blend weight minimising the blend's error
  double fitted_roughness = 0.0;  // single-interface roughness minimising its error
  double blend_fitted_alpha = 0.5;      // alpha and NDF roughness of the fitted blend
  double blend_fitted_roughness = 0.0;
  double slab_lobe_ndf_kappa = 0.0;    // the vMF concentration matched to the NDF
  double slab_lobe_light_kappa = 0.0;  // the lobe's concentration over the light directions
  double best_alpha_internal = 0.5;    // blend weight of blend_internal
  double blend_internal_fitted_alpha = 0.5;
  double blend_internal_fitted_roughness = 0.0;
  double two_interfaces_internal_weight = 0.0;  // the internal reflection's fitted weight
  // The weights of two_interfaces_internal_longer: the internal reflection's shape, the longer one.
  double longer_internal_weight = 0.0, longer_longer_weight = 0.0;
  ModelErrors errors;             // relative L2 against MC
  ModelErrors scale_free_errors;  // the same after each model's best overall scale
  // The relative L2 distance that MC noise alone would produce: sqrt(sum Omega se^2 / sum Omega mc^2).
  double mc_noise = 0.0;
  BtdfSlice mc;
  // Cell averages of each model over the slice (hemicube cell order).
  std::vector<double> rho_T, rho_B, blend, single_same_ndf, single_fitted, blend_fitted;
  std::vector<double> slab_lobe, blend_internal, blend_internal_fitted;  // empty when not computed
  std::vector<double> two_interfaces, two_interfaces_internal, two_interfaces_internal_longer;
};

struct ValidationOptions {
  // Makes the NDF of the given roughness (the same family for the slab, the model and both
  // single-interface baselines).
  std::function<std::unique_ptr<model::Ndf>(double roughness)> make_ndf;
  double roughness = 0.3;
  double eta = 1.5;
  std::vector<RoughSides> configurations = {RoughSides::kEntry, RoughSides::kExit,
                                            RoughSides::kBoth};
  std::vector<double> incidences_deg = {30.0, 45.0, 60.0};
  int cell_subdivisions = 4;  // k x k model evaluations per cell for the cell averages
  // Paths, seed (case n uses seed + n), threads and bounce cap of every MC slice.
  SliceOptions slice;
  // Also fit the blend's NDF roughness (the blend_fitted column; the slowest part, off in tests).
  bool fit_blend_roughness = true;
  // The slab-lobe column, and the internal-reflection columns (blend_internal, and
  // blend_internal_fitted when fit_blend_roughness is set too).
  bool slab_lobe = true;
  bool internal_reflection = true;
  // The two-interface columns (two_interfaces, two_interfaces_internal,
  // two_interfaces_internal_longer).
  bool two_interfaces = true;
  // The longer paths' shape is the internal reflection's with the rough sides' roughness times
  // this (the slab model's, slab_transmission.h).
  double longer_paths_widening = model::kLongerPathsWidening;
  // The internal-reflection term is smooth: it is averaged on k x k points per cell, with this
  // quadrature (a coarser one, on cell centres, inside the roughness search; the final fitted
  // column is evaluated with this one).
  int internal_subdivisions = 2;
  model::InternalReflection::Quadrature internal_quadrature;
  // Fitted roughnesses (single interface, fitted blend) are searched in [min, max] (log scale).
  double min_fitted_roughness = 0.01;
  double max_fitted_roughness = 1.5;
};

// Runs every (configuration, incidence) case on `grid`; `on_case` (optional) is called after
// each one, e.g. to report progress. Throws svbtdf::Error on invalid options.
std::vector<ValidationCase> ValidateModel(
    const ValidationOptions& options, const model::Hemicube& grid,
    const std::function<void(const ValidationCase&)>& on_case = {});

// Minimises a function of one variable on [lo, hi]: a dense scan on `scan_points` points, then a
// golden-section search in the bracket around the best one. Returns the argmin.
double MinimiseOnInterval(const std::function<double(double)>& f, double lo, double hi,
                          int scan_points = 41, double tolerance = 1e-4);

}  // namespace svbtdf::simulate
