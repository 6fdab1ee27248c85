#include "svbtdf/simulate/model_validation.h"

#include "svbtdf/common/minimize.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "svbtdf/common/error.h"
#include "svbtdf/common/least_squares.h"
#include "svbtdf/model/dual_microfacet.h"
#include "svbtdf/model/shadowing.h"
#include "svbtdf/model/slab_lobe.h"
#include "svbtdf/model/slab_transmission.h"

namespace svbtdf::simulate {
namespace {

// Solid angle of the spherical triangle with unit corners a, b, c (Van Oosterom and Strackee 1983).
double TriangleSolidAngle(const model::Vec3& a, const model::Vec3& b, const model::Vec3& c) {
  const double numerator = std::abs(a.dot(b.cross(c)));
  const double denominator = 1.0 + a.dot(b) + b.dot(c) + c.dot(a);
  return 2.0 * std::atan2(numerator, denominator);
}

// eta times the in-slab direction with the given tangential components (Snell at a flat interface).
model::Vec3 ScaledSlabDirection(double tx, double ty, double eta) {
  return {tx, ty, std::sqrt(std::max(0.0, eta * eta - tx * tx - ty * ty))};
}

// The model with its own shadowing term off: G is applied from the NDF instead.
model::DualMicrofacetModel UnshadowedModel(double eta) { return model::DualMicrofacetModel(eta, model::SmithShadowing::None()); }

// The alpha in [0, 1] minimising the error of blend_for(alpha) against MC; `scan_points` alphas
// are scanned before the golden-section refinement. *blend receives the best blend.
double BestAlpha(const std::function<std::vector<double>(double)>& blend_for, const std::vector<double>& mc,
                 const std::vector<double>& solid_angles, int scan_points, std::vector<double>* blend) {
  const double alpha = MinimiseOnInterval(
      [&](double a) { return RelativeL2Error(blend_for(a), mc, solid_angles); }, 0.0, 1.0, scan_points);
  *blend = blend_for(alpha);
  return alpha;
}

// The blend weight alpha minimising the blend's error against MC, given rho_T and rho_B at the
// averager's points; `scan_points` alphas are scanned before the golden-section refinement.
double BestBlendAlpha(const std::vector<double>& rho_T_points, const std::vector<double>& rho_B_points,
                      const CellAverager& averager, const std::vector<double>& mc,
                      const std::vector<double>& solid_angles, int scan_points,
                      std::vector<double>* blend) {
  std::vector<double> points(rho_T_points.size());
  const auto blend_for = [&](double alpha) {
    for (size_t p = 0; p < points.size(); ++p) points[p] = model::LogBlend(rho_T_points[p], rho_B_points[p], alpha);
    return averager.Average(points);
  };
  const double alpha = MinimiseOnInterval(
      [&](double a) { return RelativeL2Error(blend_for(a), mc, solid_angles); }, 0.0, 1.0,
      scan_points);
  *blend = blend_for(alpha);
  return alpha;
}

void EvaluateTerms(const model::Ndf& ndf, double eta, const std::vector<model::Vec3>& points, const model::Vec3& o,
                   std::vector<double>* rho_T, std::vector<double>* rho_B) {
  rho_T->resize(points.size());
  rho_B->resize(points.size());
  for (size_t p = 0; p < points.size(); ++p) {
    (*rho_T)[p] = RhoTWithNdfShadowing(ndf, eta, points[p], o);
    (*rho_B)[p] = RhoBWithNdfShadowing(ndf, eta, points[p], o);
  }
}

// The internal-reflection terms of both configurations at the given light directions.
struct InternalTerms {
  std::vector<double> rough_entry, rough_exit;
};

InternalTerms EvaluateInternal(const model::Ndf& ndf, const model::InternalReflection& internal,
                               const std::vector<model::Vec3>& points, const model::Vec3& o) {
  InternalTerms terms;
  terms.rough_entry.resize(points.size());
  terms.rough_exit.resize(points.size());
  for (size_t p = 0; p < points.size(); ++p) {
    terms.rough_entry[p] = internal.RoughEntry(ndf, points[p], o);
    terms.rough_exit[p] = internal.RoughExit(ndf, points[p], o);
  }
  return terms;
}

// Cell averages of LogBlend(rho_T, rho_B, alpha) + LogBlend(IR_T, IR_B, alpha): the direct terms
// on `averager`'s points, the internal ones on `halo_averager`'s.
std::vector<double> BlendWithInternal(const std::vector<double>& rho_T_points, const std::vector<double>& rho_B_points,
                                      const CellAverager& averager, const InternalTerms& internal,
                                      const CellAverager& halo_averager, double alpha) {
  std::vector<double> direct(rho_T_points.size()), halo(internal.rough_entry.size());
  for (size_t p = 0; p < direct.size(); ++p) direct[p] = model::LogBlend(rho_T_points[p], rho_B_points[p], alpha);
  for (size_t p = 0; p < halo.size(); ++p) halo[p] = model::LogBlend(internal.rough_entry[p], internal.rough_exit[p], alpha);
  std::vector<double> cells = averager.Average(direct);
  const std::vector<double> halo_cells = halo_averager.Average(halo);
  for (size_t c = 0; c < cells.size(); ++c) cells[c] += halo_cells[c];
  return cells;
}

}  // namespace

double RhoTWithNdfShadowing(const model::Ndf& ndf, double eta, const model::Vec3& i, const model::Vec3& o) {
  const model::VirtualConfiguration c = UnshadowedModel(eta).RoughEntry(i, o);
  if (!c.valid) return 0.0;
  const model::Vec3 t = ScaledSlabDirection(o.x(), o.y(), eta) / eta;
  return c.factor * ndf.D(c.h) * ndf.G1(i, c.h) * ndf.G1(t, c.h);
}

double RhoBWithNdfShadowing(const model::Ndf& ndf, double eta, const model::Vec3& i, const model::Vec3& o) {
  const model::VirtualConfiguration c = UnshadowedModel(eta).RoughExit(i, o);
  if (!c.valid) return 0.0;
  const model::Vec3 t_i = -ScaledSlabDirection(-i.x(), -i.y(), eta) / eta;  // in-slab, pointing down
  return c.factor * ndf.D(c.h) * ndf.G1(t_i, c.h) * ndf.G1(o, c.h);
}

double SingleInterfaceBtdf(const model::Ndf& ndf, double eta, const model::Vec3& i, const model::Vec3& o) {
  return model::WalterBtdf(ndf, i, o, 1.0, eta);
}

CellAverager::CellAverager(const model::Hemicube& grid, int subdivisions)
    : grid_(grid), per_cell_(subdivisions * subdivisions) {
  if (subdivisions < 1) common::ThrowInvalidInput("cell subdivisions", "must be >= 1");
  const int cells = grid.num_cells();
  directions_.reserve(static_cast<size_t>(cells) * per_cell_);
  weights_.reserve(directions_.capacity());
  const double step = 1.0 / subdivisions;
  for (int cell = 0; cell < cells; ++cell) {
    const size_t first = weights_.size();
    double cell_solid_angle = 0.0;
    for (int b = 0; b < subdivisions; ++b) {
      for (int a = 0; a < subdivisions; ++a) {
        // Hemicube cell edges are great-circle arcs, so two spherical triangles give the
        // sub-cell's solid angle exactly.
        const model::Vec3 c00 = grid.CellPoint(cell, a * step, b * step);
        const model::Vec3 c10 = grid.CellPoint(cell, (a + 1) * step, b * step);
        const model::Vec3 c11 = grid.CellPoint(cell, (a + 1) * step, (b + 1) * step);
        const model::Vec3 c01 = grid.CellPoint(cell, a * step, (b + 1) * step);
        const double solid_angle = TriangleSolidAngle(c00, c10, c11) + TriangleSolidAngle(c00, c11, c01);
        directions_.push_back(model::FlipZ(grid.CellPoint(cell, (a + 0.5) * step, (b + 0.5) * step)));
        weights_.push_back(solid_angle);
        cell_solid_angle += solid_angle;
      }
    }
    for (size_t k = first; k < weights_.size(); ++k) weights_[k] /= cell_solid_angle;
  }
}

std::vector<double> CellAverager::Average(const std::vector<double>& point_values) const {
  std::vector<double> averages(directions_.size() / per_cell_, 0.0);
  for (size_t p = 0; p < point_values.size(); ++p) averages[p / per_cell_] += weights_[p] * point_values[p];
  return averages;
}

std::vector<double> CellAverager::Average(const std::function<double(const model::Vec3& i)>& f) const {
  std::vector<double> values(directions_.size());
  for (size_t p = 0; p < directions_.size(); ++p) values[p] = f(directions_[p]);
  return Average(values);
}

double RelativeL2Error(const std::vector<double>& predicted, const std::vector<double>& reference,
                       const std::vector<double>& solid_angles) {
  double difference = 0.0;
  double norm = 0.0;
  for (size_t c = 0; c < reference.size(); ++c) {
    difference += solid_angles[c] * model::Square(predicted[c] - reference[c]);
    norm += solid_angles[c] * model::Square(reference[c]);
  }
  return norm > 0 ? std::sqrt(difference / norm) : std::numeric_limits<double>::infinity();
}

double ScaleFreeRelativeL2Error(const std::vector<double>& predicted, const std::vector<double>& reference,
                                const std::vector<double>& solid_angles) {
  double cross = 0.0;
  double model_norm = 0.0;
  for (size_t c = 0; c < reference.size(); ++c) {
    cross += solid_angles[c] * predicted[c] * reference[c];
    model_norm += solid_angles[c] * model::Square(predicted[c]);
  }
  if (!(model_norm > 0) || !(cross > 0)) return RelativeL2Error(predicted, reference, solid_angles);
  std::vector<double> scaled(predicted.size());
  for (size_t c = 0; c < predicted.size(); ++c) scaled[c] = predicted[c] * cross / model_norm;
  return RelativeL2Error(scaled, reference, solid_angles);
}

const char* ToString(RoughSides sides) {
  switch (sides) {
    case RoughSides::kEntry: return "entry";
    case RoughSides::kExit: return "exit";
    case RoughSides::kBoth: return "both";
  }
  return "?";
}

double MinimiseOnInterval(const std::function<double(double)>& f, double lo, double hi,
                          int scan_points, double tolerance) {
  if (!(hi > lo) || scan_points < 3) common::ThrowInvalidInput("interval", "needs lo < hi and >= 3 points");
  int best = 0;
  double best_value = std::numeric_limits<double>::infinity();
  const double step = (hi - lo) / (scan_points - 1);
  for (int k = 0; k < scan_points; ++k) {
    const double value = f(lo + k * step);
    if (value < best_value) {
      best_value = value;
      best = k;
    }
  }
  // Golden-section search in the bracket of the best scan point.
  const double a = lo + std::max(0, best - 1) * step;
  const double b = lo + std::min(scan_points - 1, best + 1) * step;
  const double x = common::GoldenSectionSearch(f, a, b, tolerance);
  return f(x) <= best_value ? x : lo + best * step;
}

namespace {

// What every case of one validation run shares.
struct ValidationContext {
  const ValidationOptions& options;
  const model::Ndf& ndf;
  const CellAverager& averager;
  std::vector<double> solid_angles;
  const CellAverager* halo_averager = nullptr;  // the internal-reflection term's points
  const CellAverager* centre_averager = nullptr;  // one point per cell, inside the roughness search
  double ndf_kappa = 0.0;                        // the vMF concentration matched to the NDF
};

// Seed 000's slab lobe with a vMF of the NDF's mean cosine on each rough side.
void SlabLobeColumn(const ValidationContext& context, ValidationCase* result) {
  model::SlabLobeParams params;
  params.eta = context.options.eta;
  if (result->rough_sides != RoughSides::kExit) params.kappa_entry = context.ndf_kappa;
  if (result->rough_sides != RoughSides::kEntry) params.kappa_exit = context.ndf_kappa;
  const model::SlabLobeModel lobe(params);
  result->slab_lobe_ndf_kappa = context.ndf_kappa;
  result->slab_lobe_light_kappa = lobe.LightConcentration(result->o);
  result->slab_lobe = context.averager.Average([&](const model::Vec3& i) { return lobe.Rho(i, result->o); });
}

// The blend plus the internal-reflection term, alpha and the NDF roughness fitted together. Inside
// the search the term is evaluated at cell centres with a coarse quadrature (it is smooth); the
// result is evaluated as blend_internal is.
void FitBlendInternalRoughness(const ValidationContext& context, ValidationCase* result) {
  const ValidationOptions& options = context.options;
  const std::vector<model::Vec3>& points = context.averager.light_directions();
  const model::InternalReflection coarse(options.eta, {12, 16});
  const model::InternalReflection fine(options.eta, options.internal_quadrature);
  const auto fitted_blend = [&](double log_roughness, bool final_quality, std::vector<double>* blend) {
    const std::unique_ptr<model::Ndf> trial = options.make_ndf(std::exp(log_roughness));
    std::vector<double> trial_T, trial_B;
    EvaluateTerms(*trial, options.eta, points, result->o, &trial_T, &trial_B);
    const CellAverager& halo_averager = final_quality ? *context.halo_averager : *context.centre_averager;
    const InternalTerms internal =
        EvaluateInternal(*trial, final_quality ? fine : coarse, halo_averager.light_directions(), result->o);
    return BestAlpha(
        [&](double a) { return BlendWithInternal(trial_T, trial_B, context.averager, internal, halo_averager, a); },
        result->mc.rho, context.solid_angles, final_quality ? 101 : 21, blend);
  };
  const double log_roughness = MinimiseOnInterval(
      [&](double x) {
        std::vector<double> blend;
        fitted_blend(x, false, &blend);
        return RelativeL2Error(blend, result->mc.rho, context.solid_angles);
      },
      std::log(options.min_fitted_roughness), std::log(options.max_fitted_roughness), 21, 1e-3);
  result->blend_internal_fitted_roughness = std::exp(log_roughness);
  result->blend_internal_fitted_alpha = fitted_blend(log_roughness, true, &result->blend_internal_fitted);
}

double RelativeNoise(const BtdfSlice& mc, const std::vector<double>& solid_angles) {
  double noise = 0.0;
  double norm = 0.0;
  for (size_t c = 0; c < mc.rho.size(); ++c) {
    noise += solid_angles[c] * model::Square(mc.standard_error[c]);
    norm += solid_angles[c] * model::Square(mc.rho[c]);
  }
  return std::sqrt(noise / norm);
}

// Walter's BTDF with the NDF roughness that fits the MC slice best.
void FitSingleInterface(const ValidationContext& context, ValidationCase* result) {
  const ValidationOptions& options = context.options;
  const auto single_with_roughness = [&](double log_roughness) {
    const std::unique_ptr<model::Ndf> fitted = options.make_ndf(std::exp(log_roughness));
    return context.averager.Average(
        [&](const model::Vec3& i) { return SingleInterfaceBtdf(*fitted, options.eta, i, result->o); });
  };
  const double log_roughness = MinimiseOnInterval(
      [&](double x) { return RelativeL2Error(single_with_roughness(x), result->mc.rho, context.solid_angles); },
      std::log(options.min_fitted_roughness), std::log(options.max_fitted_roughness), 41, 1e-3);
  result->fitted_roughness = std::exp(log_roughness);
  result->single_fitted = single_with_roughness(log_roughness);
}

// The blend with both alpha and the NDF roughness fitted: for each trial roughness the best alpha
// (a coarser alpha scan suffices inside the outer search).
void FitBlendRoughness(const ValidationContext& context, ValidationCase* result) {
  const ValidationOptions& options = context.options;
  const std::vector<model::Vec3>& points = context.averager.light_directions();
  const auto fitted_blend = [&](double log_roughness, std::vector<double>* blend) {
    const std::unique_ptr<model::Ndf> trial = options.make_ndf(std::exp(log_roughness));
    std::vector<double> trial_T, trial_B;
    EvaluateTerms(*trial, options.eta, points, result->o, &trial_T, &trial_B);
    return BestBlendAlpha(trial_T, trial_B, context.averager, result->mc.rho, context.solid_angles, 21,
                          blend);
  };
  const double log_roughness = MinimiseOnInterval(
      [&](double x) {
        std::vector<double> blend;
        fitted_blend(x, &blend);
        return RelativeL2Error(blend, result->mc.rho, context.solid_angles);
      },
      std::log(options.min_fitted_roughness), std::log(options.max_fitted_roughness), 21, 1e-3);
  result->blend_fitted_roughness = std::exp(log_roughness);
  result->blend_fitted_alpha = fitted_blend(log_roughness, &result->blend_fitted);
}

// The least-squares weights (>= 0) of `shapes` added to `base` against MC over the cells (solid
// angle weighted; common::NonNegativeLeastSquares).
std::vector<double> NonNegativeWeights(const ValidationCase& result, const std::vector<double>& base,
                                       const std::vector<const std::vector<double>*>& shapes,
                                       const std::vector<double>& solid_angles) {
  const int n = static_cast<int>(shapes.size());
  common::NonNegativeMatrix normal = common::NonNegativeMatrix::Zero(n, n);
  common::NonNegativeVector right = common::NonNegativeVector::Zero(n);
  for (size_t c = 0; c < base.size(); ++c) {
    for (int a = 0; a < n; ++a) {
      right[a] += solid_angles[c] * (*shapes[a])[c] * (result.mc.rho[c] - base[c]);
      for (int b = 0; b < n; ++b) normal(a, b) += solid_angles[c] * (*shapes[a])[c] * (*shapes[b])[c];
    }
  }
  const common::NonNegativeVector amounts = common::NonNegativeLeastSquares(normal, right);
  return {amounts.data(), amounts.data() + n};
}

// The slab's exact two-interface transmission; the same plus the internal reflection's shape at
// its least-squares weight over the cells (w >= 0); and the same plus the longer paths' shape too.
void TwoInterfaceColumns(const ValidationContext& context, ValidationCase* result) {
  const ValidationOptions& options = context.options;
  const std::unique_ptr<model::Ndf> flat = options.make_ndf(5e-4);
  const std::unique_ptr<model::Ndf> widened = options.make_ndf(options.longer_paths_widening * options.roughness);
  const bool entry_rough = result->rough_sides != RoughSides::kExit, exit_rough = result->rough_sides != RoughSides::kEntry;
  const model::Ndf& entry = entry_rough ? context.ndf : *flat;
  const model::Ndf& exit = exit_rough ? context.ndf : *flat;
  const model::SlabTransmission::ForViewer direct =
      model::SlabTransmission(entry, exit, options.eta).Viewer(result->o);
  // On the internal term's points (2 x 2 a cell by default): each value is an integral, and the
  // lobes of a slab with a rough side are wide.
  result->two_interfaces = context.halo_averager->Average([&](const model::Vec3& i) { return direct.Rho(i); });
  // A flat side has no T R R T term of its own: the shape is the rough side's alone.
  const model::InternalReflection paths(options.eta, {12, 12});
  const auto halo_of = [&](const model::Ndf& rough_entry, const model::Ndf& rough_exit) {
    const model::SlabInternalReflection both(rough_entry, rough_exit, options.eta);
    return context.halo_averager->Average([&](const model::Vec3& i) {
      switch (result->rough_sides) {
        case RoughSides::kEntry:
          return paths.RoughEntry(rough_entry, i, result->o);
        case RoughSides::kExit:
          return paths.RoughExit(rough_exit, i, result->o);
        case RoughSides::kBoth:
          break;
      }
      return both.Rho(i, result->o);
    });
  };
  const std::vector<double> halo = halo_of(entry, exit);
  const std::vector<double> longer = halo_of(entry_rough ? *widened : *flat, exit_rough ? *widened : *flat);
  const auto with = [&](const std::vector<double>& weights, const std::vector<const std::vector<double>*>& shapes) {
    std::vector<double> cells = result->two_interfaces;
    for (size_t s = 0; s < shapes.size(); ++s) {
      for (size_t c = 0; c < cells.size(); ++c) cells[c] += weights[s] * (*shapes[s])[c];
    }
    return cells;
  };
  const std::vector<double> one = NonNegativeWeights(*result, result->two_interfaces, {&halo}, context.solid_angles);
  result->two_interfaces_internal_weight = one[0];
  result->two_interfaces_internal = with(one, {&halo});
  const std::vector<double> two =
      NonNegativeWeights(*result, result->two_interfaces, {&halo, &longer}, context.solid_angles);
  result->longer_internal_weight = two[0];
  result->longer_longer_weight = two[1];
  result->two_interfaces_internal_longer = with(two, {&halo, &longer});
}

void ComputeErrors(const std::vector<double>& solid_angles, ValidationCase* result) {
  const std::vector<double>& mc = result->mc.rho;
  const auto both = [&](const std::vector<double>& predicted, double* error, double* scale_free_error) {
    if (predicted.empty()) return;  // a column that was not computed
    *error = RelativeL2Error(predicted, mc, solid_angles);
    *scale_free_error = ScaleFreeRelativeL2Error(predicted, mc, solid_angles);
  };
  ModelErrors& e = result->errors;
  ModelErrors& f = result->scale_free_errors;
  both(result->rho_T, &e.rho_T, &f.rho_T);
  both(result->rho_B, &e.rho_B, &f.rho_B);
  both(result->blend, &e.blend, &f.blend);
  both(result->single_same_ndf, &e.single_same_ndf, &f.single_same_ndf);
  both(result->single_fitted, &e.single_fitted, &f.single_fitted);
  both(result->blend_fitted, &e.blend_fitted, &f.blend_fitted);
  both(result->slab_lobe, &e.slab_lobe, &f.slab_lobe);
  both(result->blend_internal, &e.blend_internal, &f.blend_internal);
  both(result->blend_internal_fitted, &e.blend_internal_fitted, &f.blend_internal_fitted);
  both(result->two_interfaces, &e.two_interfaces, &f.two_interfaces);
  both(result->two_interfaces_internal, &e.two_interfaces_internal, &f.two_interfaces_internal);
  both(result->two_interfaces_internal_longer, &e.two_interfaces_internal_longer, &f.two_interfaces_internal_longer);
}

ValidationCase RunCase(const ValidationContext& context, const SlabTracer& tracer, RoughSides sides,
                       double incidence_deg, uint64_t seed) {
  const ValidationOptions& options = context.options;
  ValidationCase result;
  result.rough_sides = sides;
  result.incidence_deg = incidence_deg;
  result.o = model::SphericalDirection(incidence_deg * model::kPi / 180.0, 0.0);
  SliceOptions slice_options = options.slice;
  slice_options.seed = seed;
  result.mc = tracer.SliceForView(result.o, context.averager.grid(), slice_options);
  result.mc_noise = RelativeNoise(result.mc, context.solid_angles);

  std::vector<double> rho_T_points, rho_B_points;
  EvaluateTerms(context.ndf, options.eta, context.averager.light_directions(), result.o, &rho_T_points,
                &rho_B_points);
  result.rho_T = context.averager.Average(rho_T_points);
  result.rho_B = context.averager.Average(rho_B_points);
  result.best_alpha = BestBlendAlpha(rho_T_points, rho_B_points, context.averager, result.mc.rho,
                                     context.solid_angles, 101, &result.blend);
  result.single_same_ndf = context.averager.Average(
      [&](const model::Vec3& i) { return SingleInterfaceBtdf(context.ndf, options.eta, i, result.o); });
  FitSingleInterface(context, &result);
  if (options.fit_blend_roughness) FitBlendRoughness(context, &result);
  if (options.slab_lobe) SlabLobeColumn(context, &result);
  if (options.internal_reflection) {
    const model::InternalReflection internal(options.eta, options.internal_quadrature);
    const InternalTerms halo =
        EvaluateInternal(context.ndf, internal, context.halo_averager->light_directions(), result.o);
    result.best_alpha_internal = BestAlpha(
        [&](double a) {
          return BlendWithInternal(rho_T_points, rho_B_points, context.averager, halo, *context.halo_averager, a);
        },
        result.mc.rho, context.solid_angles, 101, &result.blend_internal);
    if (options.fit_blend_roughness) FitBlendInternalRoughness(context, &result);
  }
  if (options.two_interfaces) TwoInterfaceColumns(context, &result);
  ComputeErrors(context.solid_angles, &result);
  return result;
}

}  // namespace

std::vector<ValidationCase> ValidateModel(const ValidationOptions& options, const model::Hemicube& grid,
                                          const std::function<void(const ValidationCase&)>& on_case) {
  if (!options.make_ndf) common::ThrowInvalidInput("ndf", "no NDF factory given");
  if (!(options.eta > 1.0) || !std::isfinite(options.eta)) {
    common::ThrowInvalidInput("--eta", "must be finite and > 1, got " + std::to_string(options.eta));
  }
  for (double angle : options.incidences_deg) {
    if (!(angle >= 0.0 && angle < 90.0)) {
      common::ThrowInvalidInput("--incidence", "must lie in [0, 90) degrees, got " + std::to_string(angle));
    }
  }
  const std::unique_ptr<model::Ndf> ndf = options.make_ndf(options.roughness);
  const CellAverager averager(grid, options.cell_subdivisions);
  if (options.internal_subdivisions < 1) common::ThrowInvalidInput("internal subdivisions", "must be >= 1");
  const CellAverager halo_averager(grid, options.internal_subdivisions), centre_averager(grid, 1);
  ValidationContext context{options, *ndf, averager, std::vector<double>(grid.num_cells())};
  context.halo_averager = &halo_averager;
  context.centre_averager = &centre_averager;
  if (options.slab_lobe) context.ndf_kappa = model::MatchedVmfConcentration(*ndf);
  for (int c = 0; c < grid.num_cells(); ++c) context.solid_angles[c] = grid.CellSolidAngle(c);

  std::vector<ValidationCase> cases;
  for (RoughSides sides : options.configurations) {
    Slab slab;
    slab.eta = options.eta;
    slab.entry = sides != RoughSides::kExit ? SlabInterface::Rough(*ndf) : SlabInterface::Flat();
    slab.exit = sides != RoughSides::kEntry ? SlabInterface::Rough(*ndf) : SlabInterface::Flat();
    const SlabTracer tracer(slab);
    for (double angle : options.incidences_deg) {
      // Each case gets its own seed so that the cases' MC errors are independent.
      cases.push_back(RunCase(context, tracer, sides, angle, options.slice.seed + cases.size()));
      if (on_case) on_case(cases.back());
    }
  }
  return cases;
}

}  // namespace svbtdf::simulate
