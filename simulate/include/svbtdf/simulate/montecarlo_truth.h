#pragma once
// The Monte Carlo ground truth of `svbtdf simulate --truth montecarlo` (docs/truth-format.md,
// "Monte Carlo truth"): the sample is NOT a dual-microfacet material but a few two-interface slab
// materials laid out over the texels (an index map). Each slab material's BTDF is traced with the
// SlabTracer at a small grid of view directions spanning the camera's view of the sample and
// tabulated on a hemicube over the light directions. The truth is then the one function
//     R(x, i, o)[c] = sum_v w_v(o) sum_cell w_cell(i) S[m(x)][v][cell][c] + rho_d(x)[c]
// with w_v bilinear over the view grid (clamped outside it) and w_cell the hemicube's bilinear
// weights at FlipZ(i); S already includes the material's RGB tint. The renderer and the reader
// (`svbtdf compare`) evaluate this same function from the same float values.

#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "svbtdf/common/image_io.h"
#include "svbtdf/model/hemicube.h"
#include "svbtdf/model/ndf_factory.h"
#include "svbtdf/simulate/rig.h"
#include "svbtdf/simulate/slab_tracer.h"
#include "svbtdf/simulate/spatial_btdf.h"

namespace svbtdf::simulate {

// One interface of a slab material, as an analytic NDF by name (model/ndf_factory.h).
struct SlabInterfaceSpec {
  std::string ndf = "ggx";
  model::AnalyticNdfParams params;
};

// A two-interface slab material: the tracer's Slab plus a colour.
struct SlabMaterial {
  std::string label;
  SlabInterfaceSpec entry, exit;
  double optical_depth = 0.0;  // absorption of one crossing at normal incidence
  model::Rgb tint = {1.0, 1.0, 1.0};  // multiplies the traced (grey) rho, like k_s
  model::Rgb rho_d = {0.0, 0.0, 0.0}; // diffuse part added to R

  Slab ToSlab(double eta) const;
  // The smaller roughness of the two interfaces (how sharp the lobe can be).
  double MinRoughness() const;
};

// The materials and layout `simulate --truth montecarlo` uses; `seed` moves the layout.
std::vector<SlabMaterial> DefaultSlabMaterials();
std::vector<int> SlabIndexMap(int texels_x, int texels_y, int num_materials, uint64_t seed);

// A regular nx x ny grid of view directions over (o.x, o.y) in [x0, x1] x [y0, y1] (o.z > 0
// follows). Bilinear in (o.x, o.y): the projected direction varies smoothly and almost linearly
// with the texel position, so a few nodes follow the ±2-5 degree spread across the sample.
struct ViewGrid {
  int nx = 3, ny = 3;
  double x0 = 0, x1 = 0, y0 = 0, y1 = 0;

  int num_nodes() const { return nx * ny; }
  model::Vec3 Node(int node) const;  // node = iy * nx + ix
  // Up to four (node, weight) pairs, weights >= 0 summing to 1; o outside the grid is clamped
  // to its border. Unused entries are (0, 0.0).
  std::array<std::pair<int, double>, 4> Interpolation(const model::Vec3& o) const;
  // The grid that covers the directions from every point of the sample to the camera centre,
  // widened by a small margin for the sub-texel positions the renderer shades.
  static ViewGrid Spanning(const model::Vec3& camera_centre, const SampleConfig& sample, int nodes_per_axis);
};

// How finely each slice is traced.
struct MonteCarloPrecision {
  int hemicube_resolution = 16;
  int64_t paths = int64_t{1} << 18;  // per slice (material x view node)
  int max_interactions = 100;
};

class MonteCarloTruth final : public SpatialBtdf {
 public:
  // values / errors: per material, per view node, per hemicube cell, RGB (tint included); i.e.
  // index ((m * nodes + v) * cells + cell) * 3 + c. Throws svbtdf::Error(kInvalidInput) for
  // inconsistent sizes, an index outside the materials, or negative / non-finite values.
  MonteCarloTruth(int texels_x, int texels_y, double eta, std::vector<SlabMaterial> materials,
                  std::vector<int> index_map, std::vector<model::Rgb> rho_d, ViewGrid views,
                  int hemicube_resolution, std::vector<float> values, std::vector<float> errors);

  // Traces every material at every view node (multithreaded, deterministic for the seed).
  static MonteCarloTruth Trace(int texels_x, int texels_y, double eta,
                               std::vector<SlabMaterial> materials, std::vector<int> index_map,
                               const ViewGrid& views, const MonteCarloPrecision& precision,
                               uint64_t seed, int threads, bool progress);

  int texels_x() const override { return texels_x_; }
  int texels_y() const override { return texels_y_; }
  model::Rgb Evaluate(int index, const model::Vec3& i, const model::Vec3& o) const override;
  double MinRoughness(int index) const override;

  double eta() const { return eta_; }
  const std::vector<SlabMaterial>& materials() const { return materials_; }
  int material_of(int index) const { return index_map_[index]; }
  const model::Rgb& rho_d(int index) const { return rho_d_[index]; }
  const ViewGrid& views() const { return views_; }
  const model::Hemicube& hemicube() const { return grid_; }
  // The tabulated cell mean of the tinted rho and its standard error.
  model::Rgb SliceValue(int material, int node, int cell) const { return At(values_, material, node, cell); }
  model::Rgb SliceError(int material, int node, int cell) const { return At(errors_, material, node, cell); }
  // How it was traced (written to the manifest; 0 when unknown).
  MonteCarloPrecision precision;
  uint64_t seed = 0;
  // The worst, over all slices, of BtdfSlice::DominantRelativeError(0.9): the relative standard
  // error of the cells that hold 90% of a slice's energy (NaN when unknown).
  double dominant_relative_error = std::nan("");

 private:
  size_t Offset(int material, int node, int cell) const {
    return ((static_cast<size_t>(material) * views_.num_nodes() + node) * grid_.num_cells() + cell) * 3;
  }
  model::Rgb At(const std::vector<float>& table, int material, int node, int cell) const;

  int texels_x_, texels_y_;
  double eta_;
  std::vector<SlabMaterial> materials_;
  std::vector<int> index_map_;
  std::vector<model::Rgb> rho_d_;
  ViewGrid views_;
  model::Hemicube grid_;
  std::vector<float> values_, errors_;
};

// DIR/truth/material.json (kind "montecarlo"), index.exr, rho_d.exr and slices.exr; never
// overwrites. Read throws svbtdf::Error naming the file for anything missing or malformed.
void WriteMonteCarloTruth(const std::filesystem::path& folder, const MonteCarloTruth& truth);
MonteCarloTruth ReadMonteCarloTruth(const std::filesystem::path& folder);

// The "ndf.kind" of DIR/truth/material.json: "analytic" or "montecarlo".
std::string ReadTruthKind(const std::filesystem::path& folder);

}  // namespace svbtdf::simulate
