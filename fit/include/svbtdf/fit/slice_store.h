#pragma once
// The processed form of a capture session (docs/slice-store.md, version 1), written by
// `svbtdf process` and read by `svbtdf fit`:
//
//   PROCESSED/
//     processed.json    manifest: version, texel grid, dots, light hemicube resolution, tiling,
//                       provenance (session, options, statistics)
//     calibration.json  the session's calibration as used (calib/session_calibration.h)
//     samples.f16       R(x, i_q, o) RGB per texel and dot, float16, tiled (below); NaN = no valid
//                       measurement (saturated in every bracket, outside the image, ...)
//     slices.f16        per texel, the refractive luminance (R - rho_d) resampled by push-pull on
//                       the light hemicube (num_cells values), float16, texel-major: clustering's input
//     rho_d.exr         RGB diffuse term per texel (paper eq. 14)
//     mask.exr          1 where the texel has enough valid samples to be fitted, else 0
//
// samples.f16 is tiled so that a capture read dot by dot writes contiguous runs and a fit reads
// one tile of texels at once: tile T holds texels [T * tile, (T + 1) * tile) and is laid out
// [dot][texel in tile][channel]. Texel index = row * texels_x + col (row 0 at the sample's +y edge).
//
// Texel geometry and directions follow calib/session_calibration.h: texel centres lie in z = 0 of
// the sample frame, i_q(x) = normalize(p_q - x) (i.z < 0), o(x) = normalize(V - x).

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "svbtdf/calib/session_calibration.h"
#include "svbtdf/common/image_io.h"
#include "svbtdf/fit/texel_fit.h"
#include "svbtdf/model/dual_microfacet.h"
#include "svbtdf/model/hemicube.h"

namespace svbtdf::fit {

inline constexpr int kSliceStoreFormatVersion = 1;

// The texel grid over the sample and the directions every texel sees.
struct TexelGeometry {
  int texels_x = 0, texels_y = 0;
  double width_m = 0.0, height_m = 0.0;
  Vec3 camera_centre = Vec3::Zero();  // V, sample frame
  std::vector<Vec3> dots;             // p_q, sample frame

  int64_t num_texels() const { return static_cast<int64_t>(texels_x) * texels_y; }
  Vec3 TexelCentre(int64_t texel) const;
  Vec3 View(int64_t texel) const;              // o(x)
  Vec3 Light(int64_t texel, int dot) const;    // i_q(x)
};

struct SliceStoreInfo {
  int texels_x = 0, texels_y = 0;
  int num_dots = 0;
  int light_resolution = 16;  // light hemicube of slices.f16
  int tile_texels = 1024;
  double eta = 0.0;           // the sample's nominal eta from session.json (0: unknown)
  nlohmann::json provenance = nlohmann::json::object();
};

class SliceStore {
 public:
  // Opens and checks PROCESSED/ (svbtdf::Error naming the file on any problem, including a
  // processing that did not finish).
  static SliceStore Open(const std::filesystem::path& folder);

  const SliceStoreInfo& info() const { return info_; }
  const calib::SessionCalibration& calibration() const { return calibration_; }
  const TexelGeometry& geometry() const { return geometry_; }
  const Hemicube& light_grid() const { return light_grid_; }
  const FloatImage& rho_d() const { return rho_d_; }
  const FloatImage& mask() const { return mask_; }
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
  calib::SessionCalibration calibration_;
  TexelGeometry geometry_;
  Hemicube light_grid_{16};
  FloatImage rho_d_, mask_;
  // MakeTexelSlice from RGB samples, dot q's at rgb[q * dot_stride].
  TexelSlice SliceFromSamples(int64_t texel, const float* rgb, size_t dot_stride, const std::vector<bool>& use_dot) const;
  struct Files;
  std::shared_ptr<Files> files_;  // open file handles, shared by copies
};


// Writes PROCESSED/ dot by dot (the order images are read in), resumably: a dot counts as written
// once its values are on disk and recorded in PROCESSED/progress.jsonl.
class SliceStoreWriter {
 public:
  // Creates PROCESSED/ (new or empty folder), or resumes it when it holds an unfinished store
  // with the same info and calibration (anything else is an svbtdf::Error naming the folder).
  SliceStoreWriter(const std::filesystem::path& folder, const SliceStoreInfo& info,
                   const calib::SessionCalibration& calibration);
  ~SliceStoreWriter();
  SliceStoreWriter(SliceStoreWriter&&) noexcept;

  bool HasDot(int dot) const;
  // Dot q's R for every texel: rgb[3 * texel + c], NaN where not measured.
  void WriteDot(int dot, const std::vector<float>& rgb);

  struct FinishOptions {
    double diffuse_threshold = 0.05;  // dots brighter than this fraction of the texel's mean count for rho_d
    int min_valid_dots = 8;           // fewer valid samples: the texel is masked out
    int threads = 0;
    bool progress = true;
  };
  // After every dot: diffuse separation, push-pull slices, maps, manifest; the store is then
  // complete and SliceStore::Open accepts it.
  void Finish(const FinishOptions& options);

 private:
  struct State;
  std::unique_ptr<State> state_;
};

TexelGeometry MakeTexelGeometry(const calib::SessionCalibration& calibration, int texels_x, int texels_y);

}  // namespace svbtdf::fit
