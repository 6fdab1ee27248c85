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
//     rho_d.exr         RGB diffuse term per texel (the floor of the samples, EstimateDiffuse below)
//     mask.exr          1 where the texel has enough valid samples to be fitted, else 0
//     reach.exr         1 where a dot lies beneath the texel (TexelsWithDotBeneath below), else 0
//
// samples.f16 is tiled so that a capture read dot by dot writes contiguous runs and a fit reads
// one tile of texels at once: tile T holds texels [T * tile, (T + 1) * tile) and is laid out
// [dot][texel in tile][channel]. Texel index = row * texels_x + col (row 0 at the sample's +y edge).
//
// Texel geometry and directions follow calib/session_calibration.h: texel centres lie in z = 0 of
// the sample frame, i_q(x) = normalize(p_q - x) (i.z < 0), o(x) = normalize(V - x).

#include <array>
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
  Vec3 monitor_normal = Vec3::UnitZ();  // the monitor plane's normal (the plane holds the dots)

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
  // 1 where a dot lies beneath the texel, else 0 (reach.exr; recomputed from the geometry for a
  // store written before reach.exr existed).
  const FloatImage& reach() const { return reach_; }
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
  FloatImage rho_d_, mask_, reach_;
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
    double diffuse_threshold = 0.05;  // dots whose 1 / s_q (EstimateDiffuse) is below this fraction of the texel's largest do not count for rho_d
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

// Whether a dot lies beneath each texel: for a thin slab with parallel faces the transmitted
// lobe peaks in the view direction itself, so the texel's lobe peak is where the camera's ray
// through the texel centre, continued, meets the monitor plane. A dot lies beneath the texel when
// that point is inside the dot grid's footprint: within half a dot spacing (the median
// nearest-neighbour distance) of the dots' convex hull, and within half a diagonal of a grid cell
// (spacing / sqrt 2) of its nearest dot, so that a hole in the grid counts as outside.
// One value per texel (index row * texels_x + col): 1 = a dot beneath, 0 = none.
std::vector<uint8_t> TexelsWithDotBeneath(const TexelGeometry& geometry);

// The diffuse term of one texel from samples R_q = k_s lobe_q + rho_d + noise_q (docs/slice-store.md,
// "Diffuse separation"). `noise_scale[q]` is s_q = |p_q - x|^2 / (|i_q.z| P(theta_q)), the factor
// that turns the camera's rate into R: under shot noise Var(R_q) = c s_q E[R_q] with one unknown c
// per texel. `neighbours[q]` are the samples of two dots on either side of q's on the grid
// ({-1, -1}: none): the lobe is smooth from dot to dot and the noise is not, so the median of the
// second differences R_q - (R_a + R_b) / 2 over the floor set measures c whatever the lobe.
// The floor is the set of samples within `clip` standard deviations (sqrt(c floor s_q)) of its
// inverse-variance weighted mean, found by iterating from the lowest tenth of the samples;
// symmetric clipping keeps the mean unbiased for symmetric noise, where the paper's minimum
// (eq. 14) takes the most negative noise draw. Selection is on luminance; each channel is the
// weighted mean over the set.
struct DiffuseEstimate {
  Rgb rho_d = {0, 0, 0};
  int floor_samples = 0;  // samples in the floor set
  double spread = 0.0;    // the noise's standard deviation on the floor, in units of sqrt(s_q)
};
DiffuseEstimate EstimateDiffuse(const std::vector<Rgb>& r, const std::vector<double>& noise_scale,
                                const std::vector<std::array<int, 2>>& neighbours, double clip = 2.5);
// For every dot, two dots on either side of it along one of the grid's directions (the nearest
// dot and the one at its mirror image), or {-1, -1} when the grid has none (its corners).
std::vector<std::array<int, 2>> OppositeNeighbours(const std::vector<Vec3>& dots);

}  // namespace svbtdf::fit
