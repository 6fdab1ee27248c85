#pragma once
// The processed form of a capture session (docs/slice-store.md, version 2), written by
// `svbtdf process` (process/slice_store_writer.h) and read here, by `svbtdf fit`:
//
//   PROCESSED/
//     processed.json    manifest: version, texel grid, dots, light hemicube resolution, tiling,
//                       the texel geometry (camera centre, dots), provenance, statistics
//     calibration.json  the session's calibration as used (for the record and for resuming)
//     samples.f16       R(x, i_q, o) RGB per texel and dot, float16, tiled (below); NaN = no valid
//                       measurement (saturated in every bracket, outside the image, ...)
//     slices.f16        per texel, the refractive luminance (R - rho_d) resampled by push-pull on
//                       the light hemicube (num_cells values), float16, texel-major: clustering's input
//     rho_d.exr         RGB diffuse term per texel (the floor of the samples: process/diffuse_separation.h)
//     mask.exr          1 where the texel has enough valid samples to be fitted, else 0
//     reach.exr         1 where a dot lies beneath the texel (process/slice_store_writer.h, TexelsWithDotBeneath), else 0
//
// samples.f16 is tiled so that a capture read dot by dot writes contiguous runs and a fit reads
// one tile of texels at once: tile T holds texels [T * tile, (T + 1) * tile) and is laid out
// [dot][texel in tile][channel]. Texel index = row * texels_x + col (row 0 at the sample's +y edge).
//
// Texel geometry and directions follow the calibration's sample frame (docs/calibration-format.md):
// texel centres lie in z = 0 of the sample frame, i_q(x) = normalize(p_q - x) (i.z < 0), o(x) = normalize(V - x).

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "svbtdf/common/image_io.h"
#include "svbtdf/fit/texel_fit.h"
#include "svbtdf/model/dual_microfacet.h"
#include "svbtdf/model/hemicube.h"

namespace svbtdf::fit {

// Version 2 records the texel geometry in processed.json, so that opening a store needs no
// calibration; version 1 stores are refused (re-run `svbtdf process`).
inline constexpr int kSliceStoreFormatVersion = 2;

// The texel grid over the sample and the directions every texel sees.
struct TexelGeometry {
  int texels_x = 0, texels_y = 0;
  double width_m = 0.0, height_m = 0.0;
  model::Vec3 camera_centre = model::Vec3::Zero();  // V, sample frame
  std::vector<model::Vec3> dots;             // p_q, sample frame
  model::Vec3 monitor_normal = model::Vec3::UnitZ();  // the monitor plane's normal (the plane holds the dots)

  int64_t num_texels() const { return static_cast<int64_t>(texels_x) * texels_y; }
  model::Vec3 TexelCentre(int64_t texel) const;
  model::Vec3 View(int64_t texel) const;              // o(x)
  model::Vec3 Light(int64_t texel, int dot) const;    // i_q(x)
  // The area of monitor one dot stands for: the median nearest-neighbour spacing of the dots,
  // squared (1e-4 m^2 for fewer than two dots).
  double DotCellArea() const;
};

struct SliceStoreInfo {
  int texels_x = 0, texels_y = 0;
  int num_dots = 0;
  int light_resolution = 16;  // light hemicube of slices.f16
  int tile_texels = 1024;
  double eta = 0.0;           // the sample's nominal eta from session.json (0: unknown)
  // The relative standard deviation, per channel, of a texel's white exitance from the flat
  // white capture, which divides every sample of the texel alike (docs/slice-store.md, "The
  // flat white's noise"); 0 where not measured (stores written before it).
  std::array<double, 3> white_exitance_noise = {0.0, 0.0, 0.0};
  nlohmann::json provenance = nlohmann::json::object();
};

class SliceStore {
 public:
  // Opens and checks PROCESSED/ (svbtdf::Error naming the file on any problem, including a
  // processing that did not finish).
  static SliceStore Open(const std::filesystem::path& folder);

  const SliceStoreInfo& info() const { return info_; }
  const TexelGeometry& geometry() const { return geometry_; }
  const model::Hemicube& light_grid() const { return light_grid_; }
  const common::FloatImage& rho_d() const { return rho_d_; }
  const common::FloatImage& mask() const { return mask_; }
  // 1 where a dot lies beneath the texel, else 0 (reach.exr).
  const common::FloatImage& reach() const { return reach_; }
  const std::filesystem::path& folder() const { return folder_; }

  // RGB R of every dot for one texel: out[3 * q + c]; NaN where there is no valid measurement.
  void ReadSamples(int64_t texel, std::vector<float>* out) const;
  // One tile's samples at once, [dot][texel in tile][channel] (faster when fitting many texels).
  void ReadTile(int64_t tile, std::vector<float>* out) const;
  // The texel's resampled refractive luminance slice over light_grid() cells.
  void ReadSlice(int64_t texel, float* out) const;

  // The fit's input for one texel: the refractive part R - rho_d at every valid dot whose
  // `use_dot[q]` is true (all when empty), with the texel's own view and light directions.
  TexelSlice MakeTexelSlice(int64_t texel, const std::vector<bool>& use_dot = {}) const;
  // The same from the samples of the texel's tile, as ReadTile gives them: reading a texel on its
  // own takes one small read per dot (the store is dot-major within a tile), so code that visits
  // every texel reads each tile once instead.
  TexelSlice MakeTexelSlice(int64_t texel, const std::vector<float>& tile_samples,
                            const std::vector<bool>& use_dot = {}) const;

 private:
  std::filesystem::path folder_;
  SliceStoreInfo info_;
  TexelGeometry geometry_;
  model::Hemicube light_grid_{16};
  common::FloatImage rho_d_, mask_, reach_;
  // MakeTexelSlice from RGB samples, dot q's at rgb[q * dot_stride].
  TexelSlice SliceFromSamples(int64_t texel, const float* rgb, size_t dot_stride, const std::vector<bool>& use_dot) const;
  struct Files;
  std::shared_ptr<Files> files_;  // open file handles, shared by copies
};


}  // namespace svbtdf::fit
