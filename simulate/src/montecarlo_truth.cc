#include "svbtdf/simulate/montecarlo_truth.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include "svbtdf/common/error.h"
#include "svbtdf/common/progress.h"
#include "svbtdf/common/random.h"

namespace svbtdf::simulate {
namespace {


// Every slice gets its own seed, so that slices are independent and a material's slices do not
// change when another material is added.
uint64_t SliceSeed(uint64_t seed, int material, int node) {
  return common::SplitMix64(common::SplitMix64(common::SplitMix64(seed) ^ static_cast<uint64_t>(material)) ^ static_cast<uint64_t>(node));
}

double InterfaceRoughness(const SlabInterfaceSpec& spec) {
  // vMF with concentration kappa has an angular spread of about 1/sqrt(kappa) radians.
  if (spec.ndf == "vmf") return 1.0 / std::sqrt(std::max(spec.params.kappa, 1e-12));
  return std::min(spec.params.alpha_x, spec.params.alpha_y);
}

// Float quantisation up front, so that the in-memory truth the renderer evaluates is bit for bit
// the one written to and read back from the EXR maps.
model::Rgb ToFloat(const model::Rgb& rgb) {
  return {static_cast<float>(rgb[0]), static_cast<float>(rgb[1]), static_cast<float>(rgb[2])};
}

}  // namespace

Slab SlabMaterial::ToSlab(double eta) const {
  Slab slab;
  slab.eta = eta;
  slab.entry = SlabInterface::Rough(*model::MakeAnalyticNdf(entry.ndf, entry.params));
  slab.exit = SlabInterface::Rough(*model::MakeAnalyticNdf(exit.ndf, exit.params));
  slab.optical_depth = optical_depth;
  return slab;
}

double SlabMaterial::MinRoughness() const {
  return std::min(InterfaceRoughness(entry), InterfaceRoughness(exit));
}

std::vector<SlabMaterial> DefaultSlabMaterials() {
  // Three slabs that no dual-microfacet texel reproduces exactly: different NDF families on the
  // two sides, anisotropy on one side only, a skewed lobe, some absorption.
  SlabMaterial frosted;
  frosted.label = "frosted: isotropic GGX 0.30 entry, GGX 0.12 exit, light absorption";
  frosted.entry.params.alpha_x = frosted.entry.params.alpha_y = 0.30;
  frosted.exit.params.alpha_x = frosted.exit.params.alpha_y = 0.12;
  frosted.optical_depth = 0.02;
  frosted.tint = {0.92, 0.90, 0.86};
  frosted.rho_d = {0.01, 0.01, 0.01};

  SlabMaterial brushed;
  brushed.label = "brushed: anisotropic GGX 0.08 x 0.35 entry, Beckmann 0.15 exit";
  brushed.entry.params.alpha_x = 0.08;
  brushed.entry.params.alpha_y = 0.35;
  brushed.exit.ndf = "beckmann";
  brushed.exit.params.alpha_x = brushed.exit.params.alpha_y = 0.15;
  brushed.tint = {0.88, 0.92, 0.95};
  brushed.rho_d = {0.005, 0.005, 0.005};

  SlabMaterial skewed;
  skewed.label = "skewed: ellipsoid 0.25 x 0.18 tilted entry, GGX 0.20 exit, absorbing";
  skewed.entry.ndf = "ellipsoid";
  skewed.entry.params = {.alpha_x = 0.25, .alpha_y = 0.18, .theta_x = 0.15, .theta_y = -0.1, .theta_z = 0.4};
  skewed.exit.params.alpha_x = skewed.exit.params.alpha_y = 0.20;
  skewed.optical_depth = 0.05;
  skewed.tint = {0.95, 0.85, 0.75};
  skewed.rho_d = {0.02, 0.015, 0.01};
  return {frosted, brushed, skewed};
}

std::vector<int> SlabIndexMap(int texels_x, int texels_y, int num_materials, uint64_t seed) {
  // A disc of material 1 over a vertical boundary between 0 (left) and 2 (right); the seed moves
  // the disc and the boundary by up to 8% of the width, so seeds give different layouts.
  const auto jitter = [&](int k) { return 0.16 * ((common::SplitMix64(common::SplitMix64(seed) + k) >> 11) * 0x1.0p-53 - 0.5); };
  const double cx = 0.5 + jitter(1), cy = 0.5 + jitter(2), boundary = 0.5 + jitter(3);
  const double aspect = static_cast<double>(texels_y) / texels_x;
  std::vector<int> map(static_cast<size_t>(texels_x) * texels_y);
  for (int row = 0; row < texels_y; ++row) {
    for (int col = 0; col < texels_x; ++col) {
      const double u = (col + 0.5) / texels_x, v = (row + 0.5) / texels_y;
      const bool disc = std::hypot(u - cx, (v - cy) * aspect) < 0.28;
      const int material = disc ? 1 : u < boundary ? 0 : 2;
      map[static_cast<size_t>(row) * texels_x + col] = material % num_materials;
    }
  }
  return map;
}

model::Vec3 ViewGrid::Node(int node) const {
  const int ix = node % nx, iy = node / nx;
  const double ox = x0 + (x1 - x0) * ix / (nx - 1), oy = y0 + (y1 - y0) * iy / (ny - 1);
  return {ox, oy, std::sqrt(std::max(0.0, 1.0 - ox * ox - oy * oy))};
}

std::array<std::pair<int, double>, 4> ViewGrid::Interpolation(const model::Vec3& o) const {
  // Continuous node coordinates, clamped to the grid, then the cell [i, i + 1] holding them.
  const auto axis = [](double value, double lo, double hi, int n) {
    const double f = std::clamp((value - lo) / (hi - lo) * (n - 1), 0.0, n - 1.0);
    const int i = std::min(static_cast<int>(f), n - 2);
    return std::pair<int, double>{i, f - i};
  };
  const auto [ix, tx] = axis(o.x(), x0, x1, nx);
  const auto [iy, ty] = axis(o.y(), y0, y1, ny);
  return {{{iy * nx + ix, (1 - tx) * (1 - ty)},
           {iy * nx + ix + 1, tx * (1 - ty)},
           {(iy + 1) * nx + ix, (1 - tx) * ty},
           {(iy + 1) * nx + ix + 1, tx * ty}}};
}

ViewGrid ViewGrid::Spanning(const model::Vec3& camera_centre, const SampleConfig& sample, int nodes_per_axis) {
  if (nodes_per_axis < 2) common::ThrowInvalidInput("view grid", "needs at least 2 nodes per axis");
  ViewGrid grid;
  grid.nx = grid.ny = nodes_per_axis;
  grid.x0 = grid.y0 = 1e300;
  grid.x1 = grid.y1 = -1e300;
  // o varies smoothly over the plane; a fine sampling of the rectangle, edges included, finds its
  // extremes to far below the margin.
  constexpr int kSteps = 16;
  for (int a = 0; a <= kSteps; ++a) {
    for (int b = 0; b <= kSteps; ++b) {
      const model::Vec3 p((a / double(kSteps) - 0.5) * sample.width, (b / double(kSteps) - 0.5) * sample.height(), 0.0);
      const model::Vec3 o = (camera_centre - p).normalized();
      grid.x0 = std::min(grid.x0, o.x());
      grid.x1 = std::max(grid.x1, o.x());
      grid.y0 = std::min(grid.y0, o.y());
      grid.y1 = std::max(grid.y1, o.y());
    }
  }
  const double margin_x = 0.02 * (grid.x1 - grid.x0) + 1e-4, margin_y = 0.02 * (grid.y1 - grid.y0) + 1e-4;
  grid.x0 -= margin_x;
  grid.x1 += margin_x;
  grid.y0 -= margin_y;
  grid.y1 += margin_y;
  return grid;
}

MonteCarloTruth::MonteCarloTruth(int texels_x, int texels_y, double eta, std::vector<SlabMaterial> materials,
                                 std::vector<int> index_map, std::vector<model::Rgb> rho_d, ViewGrid views,
                                 int hemicube_resolution, std::vector<float> values, std::vector<float> errors)
    : texels_x_(texels_x), texels_y_(texels_y), eta_(eta), materials_(std::move(materials)),
      index_map_(std::move(index_map)), rho_d_(std::move(rho_d)), views_(views), grid_(hemicube_resolution),
      values_(std::move(values)), errors_(std::move(errors)) {
  const std::string subject = "Monte Carlo truth";
  if (texels_x < 1 || texels_y < 1) common::ThrowInvalidInput(subject, "needs at least 1 x 1 texels");
  if (!(eta > 1.0) || !std::isfinite(eta)) common::ThrowInvalidInput(subject, "eta must be > 1");
  if (materials_.empty()) common::ThrowInvalidInput(subject, "needs at least one slab material");
  const size_t texels = static_cast<size_t>(texels_x) * texels_y;
  if (index_map_.size() != texels || rho_d_.size() != texels) {
    common::ThrowInvalidInput(subject, "index or rho_d map does not have " + std::to_string(texels) + " texels");
  }
  for (int m : index_map_) {
    if (m < 0 || m >= static_cast<int>(materials_.size())) {
      common::ThrowInvalidInput(subject, "index map names material " + std::to_string(m) + " of " +
                                     std::to_string(materials_.size()));
    }
  }
  if (views_.nx < 2 || views_.ny < 2 || !(views_.x1 > views_.x0) || !(views_.y1 > views_.y0)) {
    common::ThrowInvalidInput(subject, "the view grid needs 2 x 2 nodes or more over a non-empty range");
  }
  const size_t expected = materials_.size() * views_.num_nodes() * grid_.num_cells() * 3;
  if (values_.size() != expected || errors_.size() != expected) {
    common::ThrowInvalidInput(subject, "slice tables hold " + std::to_string(values_.size()) + " values, expected " +
                                   std::to_string(expected));
  }
  const auto bad = [](float v) { return !(v >= 0.0f) || !std::isfinite(v); };
  if (std::any_of(values_.begin(), values_.end(), bad) || std::any_of(errors_.begin(), errors_.end(), bad)) {
    common::ThrowInvalidInput(subject, "slice values and errors must be finite and >= 0");
  }
  for (model::Rgb& rgb : rho_d_) rgb = ToFloat(rgb);
}

MonteCarloTruth MonteCarloTruth::Trace(int texels_x, int texels_y, double eta, std::vector<SlabMaterial> materials,
                                       std::vector<int> index_map, const ViewGrid& views,
                                       const MonteCarloPrecision& precision, uint64_t seed, int threads,
                                       bool progress) {
  const model::Hemicube grid(precision.hemicube_resolution);
  const int nodes = views.num_nodes(), cells = grid.num_cells();
  const size_t size = materials.size() * nodes * cells * 3;
  std::vector<float> values(size), errors(size);
  std::optional<common::ProgressBar> bar;
  if (progress) bar.emplace("tracing the Monte Carlo truth", static_cast<int64_t>(materials.size()) * nodes, "slices");
  double worst_error = 0.0;
  for (size_t m = 0; m < materials.size(); ++m) {
    const SlabTracer tracer(materials[m].ToSlab(eta));
    for (int v = 0; v < nodes; ++v) {
      SliceOptions options;
      options.paths = precision.paths;
      options.seed = SliceSeed(seed, static_cast<int>(m), v);
      options.threads = threads;
      options.max_interactions = precision.max_interactions;
      const BtdfSlice slice = tracer.SliceForView(views.Node(v), grid, options);
      worst_error = std::max(worst_error, slice.DominantRelativeError(0.9));
      for (int cell = 0; cell < cells; ++cell) {
        const size_t at = ((m * nodes + v) * cells + cell) * 3;
        for (int c = 0; c < 3; ++c) {
          values[at + c] = static_cast<float>(materials[m].tint[c] * slice.rho[cell]);
          errors[at + c] = static_cast<float>(materials[m].tint[c] * slice.standard_error[cell]);
        }
      }
      if (bar) bar->Advance();
    }
  }
  if (bar) bar->Finish();
  std::vector<model::Rgb> rho_d(index_map.size());
  for (size_t t = 0; t < index_map.size(); ++t) rho_d[t] = materials.at(index_map[t]).rho_d;
  MonteCarloTruth truth(texels_x, texels_y, eta, std::move(materials), std::move(index_map), std::move(rho_d),
                        views, precision.hemicube_resolution, std::move(values), std::move(errors));
  truth.precision = precision;
  truth.seed = seed;
  truth.dominant_relative_error = worst_error;
  return truth;
}

model::Rgb MonteCarloTruth::At(const std::vector<float>& table, int material, int node, int cell) const {
  const size_t at = Offset(material, node, cell);
  return {table[at], table[at + 1], table[at + 2]};
}

model::Rgb MonteCarloTruth::Evaluate(int index, const model::Vec3& i, const model::Vec3& o) const {
  const int material = index_map_[index];
  const auto view_weights = views_.Interpolation(o);
  // The slices are tabulated at the cells of FlipZ(i) (SlabTracer::SliceForView).
  const model::Hemicube::Weights light_weights = grid_.Interpolation(model::FlipZ(i));
  model::Rgb result = rho_d_[index];
  for (const auto& [node, wv] : view_weights) {
    if (wv <= 0.0) continue;
    for (const auto& [cell, wc] : light_weights) {
      if (wc <= 0.0) continue;
      const float* value = &values_[Offset(material, node, cell)];
      for (int c = 0; c < 3; ++c) result[c] += wv * wc * value[c];
    }
  }
  return result;
}

double MonteCarloTruth::MinRoughness(int index) const { return materials_[index_map_[index]].MinRoughness(); }

}  // namespace svbtdf::simulate
