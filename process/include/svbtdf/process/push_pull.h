#pragma once
// Push-pull resampling (Gortler et al. 1996) of one texel's scattered light samples onto the
// light hemicube, as the dual-microfacet paper does before fitting and clustering (Sec. 4.1).
//
// The hemicube is unfolded into a cross-shaped 2N x 2N image (the top face in the middle, the
// four side faces as its arms), so that one image pyramid serves the whole hemisphere and cells
// on either side of a top-face edge are neighbours. Samples are splatted bilinearly; "pull"
// builds coarser levels of weighted means with weights clamped to 1; "push" fills every fine cell
// whose weight is below 1 from the level above, in proportion to the missing weight.

#include <vector>

#include "svbtdf/model/hemicube.h"
#include "svbtdf/model/vec.h"

namespace svbtdf::process {

class PushPullResampler {
 public:
  // The light grid's resolution must be a power of two (the pyramid halves it down to 1).
  explicit PushPullResampler(const model::Hemicube& light_grid);

  const model::Hemicube& grid() const { return grid_; }

  // Samples at light directions i (i.z < 0) with values and weights (0 = missing). Writes one
  // value per hemicube cell of FlipZ(i) and the splatted weight that supports it (its
  // confidence: >= 1 means the cell is covered by data, small values mean pushed-in guesses).
  void Resample(const std::vector<model::Vec3>& light, const std::vector<float>& values,
                const std::vector<float>& weights, std::vector<float>* cell_values,
                std::vector<float>* cell_confidence) const;

 private:
  model::Hemicube grid_;
  int size_;                       // 2N: side of the unfolded image
  std::vector<int> pixel_of_cell_;  // row * size_ + col of each cell in the unfolded image
};

}  // namespace svbtdf::process
