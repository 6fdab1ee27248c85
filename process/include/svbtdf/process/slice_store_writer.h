#pragma once
// Writes the slice store (docs/slice-store.md; the format is fit/slice_store.h's, which reads it):
// the samples dot by dot as processing produces them, then the diffuse separation, the push-pull
// slices and the maps.

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <vector>

#include "svbtdf/calib/session_calibration.h"
#include "svbtdf/fit/slice_store.h"

namespace svbtdf::process {

// Writes PROCESSED/ dot by dot (the order images are read in), resumably: a dot counts as written
// once its values are on disk and recorded in PROCESSED/progress.jsonl. Written dots are made
// durable together, about once a second (a group commit), and when the writer finishes or is
// destroyed; a crash loses at most the last second's dots, which the next run processes again.
class SliceStoreWriter {
 public:
  // Creates PROCESSED/ (new or empty folder), or resumes it when it holds an unfinished store
  // with the same info and calibration, or finds it finished() when it holds that store complete
  // (anything else is an svbtdf::Error naming the folder).
  SliceStoreWriter(const std::filesystem::path& folder, const fit::SliceStoreInfo& info,
                   const calib::SessionCalibration& calibration);
  ~SliceStoreWriter();
  SliceStoreWriter(SliceStoreWriter&&) noexcept;

  // The folder holds this very store, complete: there is nothing to write.
  bool finished() const;
  bool HasDot(int dot) const;
  // Dot q's R for every texel: rgb[3 * texel + c], NaN where not measured. HasDot(dot) is true
  // from then on; the dot is durable after the next Commit.
  void WriteDot(int dot, const std::vector<float>& rgb);
  // Makes every written dot durable: fsyncs the samples, then records the dots in the journal.
  void Commit();

  struct FinishOptions {
    double diffuse_threshold = 0.05;  // dots whose 1 / s_q (EstimateDiffuse) is below this fraction of the texel's largest do not count for rho_d
    int min_valid_dots = 8;           // fewer valid samples: the texel is masked out
    int threads = 0;
    bool progress = true;
    // For a polarised screen: what processing divided the sample of light direction `light` at
    // `texel` by (the polarised over the unpolarised transmission of the lobe's configurations).
    // The diffuse floor is the same for every polarisation (the model's rho_d, as the simulator
    // renders it), so it is estimated from the samples multiplied back by it. Empty: unpolarised.
    std::function<double(const model::Vec3& light, int64_t texel)> polarisation_ratio;
    // Recorded in the manifest (SliceStoreInfo::white_exitance_noise; WhiteExitanceNoise).
    std::array<double, 3> white_exitance_noise = {0.0, 0.0, 0.0};
  };
  // After every dot: diffuse separation, push-pull slices, maps, manifest; the store is then
  // complete and SliceStore::Open accepts it.
  void Finish(const FinishOptions& options);

 private:
  struct State;
  std::unique_ptr<State> state_;
};

// The texel grid over the calibrated sample and the directions every texel sees.
fit::TexelGeometry MakeTexelGeometry(const calib::SessionCalibration& calibration, int texels_x, int texels_y);

// Whether a dot lies beneath each texel: for a thin slab with parallel faces the transmitted
// lobe peaks in the view direction itself, so the texel's lobe peak is where the camera's ray
// through the texel centre, continued, meets the monitor plane. A dot lies beneath the texel when
// that point is inside the dot grid's footprint: within half a dot spacing (the median
// nearest-neighbour distance) of the dots' convex hull, and within half a diagonal of a grid cell
// (spacing / sqrt 2) of its nearest dot, so that a hole in the grid counts as outside.
// One value per texel (index row * texels_x + col): 1 = a dot beneath, 0 = none.
std::vector<uint8_t> TexelsWithDotBeneath(const fit::TexelGeometry& geometry);

}  // namespace svbtdf::process
