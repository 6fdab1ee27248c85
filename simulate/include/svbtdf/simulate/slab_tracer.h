#pragma once
// Monte Carlo ground truth for the BTDF of a thin slab with two independent rough interfaces
// (docs/validation.md, "The Monte Carlo reference"). The slab is infinitely wide and thin: a BTDF
// is a distribution over directions, so the lateral offset between the two interface hits does not
// matter and the tracer only follows directions.
//
// Frame and conventions are those of docs/model.md: z is the macro normal and points toward the
// camera; the entry interface faces the light (below), the exit interface faces the camera (above);
// i points toward the light (i.z < 0), o toward the camera (o.z > 0); eta = n_slab / n_air > 1.
// Both interfaces describe their microfacet normals h in this one sample frame, on the upper
// hemisphere (h.z > 0), exactly as the model's D(h_T) and D(h_B) do, so that an NDF handed to the
// tracer and to the model means the same surface.
//
// At every interface hit the tracer samples a normal visible from the arriving direction, picks
// reflection or refraction with the Fresnel probability, and multiplies the path's throughput by
// the sampler weight and by the Smith G1 of the outgoing direction. This is an unbiased estimator of
// the single-scattering microfacet BSDF of Walter et al. 2007 with separable Smith shadowing (the
// derivation is in docs/validation.md); the energy that the masking term removes is reported as
// `masked`.

#include <cstdint>
#include <memory>
#include <vector>

#include "svbtdf/model/hemicube.h"
#include "svbtdf/model/ndf.h"
#include "svbtdf/model/vec.h"
#include "svbtdf/common/random.h"

namespace svbtdf::simulate {

// One interface of the slab: rough with an NDF, or perfectly flat (no NDF).
struct SlabInterface {
  std::shared_ptr<const model::Ndf> ndf;  // null: flat

  static SlabInterface Flat() { return {}; }
  static SlabInterface Rough(const model::Ndf& ndf) { return {std::shared_ptr<const model::Ndf>(ndf.Clone())}; }
  bool flat() const { return ndf == nullptr; }
};

struct Slab {
  double eta = 1.5;           // n_slab / n_air, > 1
  SlabInterface entry;        // faces the light
  SlabInterface exit;         // faces the camera
  // Absorption: optical depth of one crossing at normal incidence; a crossing along an in-slab
  // direction t is attenuated by exp(-optical_depth / |t.z|).
  double optical_depth = 0.0;
};

// Where the unit energy of one path went. transmitted + reflected + absorbed + masked + capped = 1.
struct EnergyFractions {
  double transmitted = 0.0;  // left through the far side
  double reflected = 0.0;    // left back through the side it came from
  double absorbed = 0.0;     // absorbed in the bulk
  double masked = 0.0;       // removed by Smith masking (and by a sampler weight < 1); it is what
                             // multiple scattering on the microsurface would redistribute
  double capped = 0.0;       // still inside the slab when the interaction cap was reached
  double Total() const { return transmitted + reflected + absorbed + masked + capped; }
};

// The fate of one path.
struct PathRecord {
  bool left_slab = false;    // true: it left, along `direction`
  bool transmitted = false;  // it left through the far side
  model::Vec3 direction = model::Vec3::Zero();  // travel direction on leaving (unit)
  int interactions = 0;           // interface hits
  EnergyFractions energy;         // this path's unit energy, split
};

struct SliceOptions {
  // Number of paths; with a target error, the largest number to trace.
  int64_t paths = int64_t{1} << 22;
  // > 0: stop after the first batch of paths (kBatchPaths) after which DominantRelativeError()
  // is at most this value.
  double target_relative_error = 0.0;
  // The cells that together hold this fraction of the transmitted energy are the "dominant"
  // cells whose relative standard error the target refers to.
  double dominant_energy_fraction = 0.9;
  uint64_t seed = 1;
  int threads = 0;              // 0: every hardware thread
  int max_interactions = 100;   // the bounce cap: interface hits before a path counts as capped
  bool show_progress = false;   // a ProgressBar on stderr
};

// A BTDF slice tabulated on a hemicube: rho averaged over each cell, with its standard error.
struct BtdfSlice {
  std::vector<double> rho;             // mean of rho over the cell, per hemicube cell
  std::vector<double> standard_error;  // standard error of that mean
  std::vector<double> energy;          // fraction of the incident energy that left through the cell
  std::vector<int64_t> hits;           // number of paths that left through the cell
  EnergyFractions fractions;           // means over all paths
  EnergyFractions fractions_standard_error;
  int64_t paths = 0;
  double seconds = 0.0;

  // The largest relative standard error among the fewest cells, taken by decreasing energy, that
  // together hold `energy_fraction` of the transmitted energy. Infinity when nothing was
  // transmitted.
  double DominantRelativeError(double energy_fraction) const;
};

class SlabTracer {
 public:
  // Paths are traced in chunks of this many, each with its own random stream Pcg32(seed, chunk).
  static constexpr int64_t kChunkPaths = int64_t{1} << 14;
  // With a target error the stopping rule is checked after every batch of this many paths.
  static constexpr int64_t kBatchPaths = int64_t{1} << 20;

  // Throws svbtdf::Error(kInvalidInput) for eta <= 1 or a negative or non-finite optical depth.
  explicit SlabTracer(Slab slab);

  const Slab& slab() const { return slab_; }

  // Traces one path that arrives travelling along the unit `direction`: direction.z < 0 arrives
  // from the camera side on the exit interface, direction.z > 0 from the light side on the entry.
  PathRecord TracePath(const model::Vec3& direction, common::Pcg32& rng, int max_interactions) const;

  // rho(i, o) for the fixed view direction o (o.z > 0) over the light hemisphere, tabulated on
  // `grid` at the cells of FlipZ(i). Traced from the camera side (paths arrive along -o); by the
  // reciprocity of the air-slab-air BTDF the density of exit directions i is rho(i, o) |i.z|.
  BtdfSlice SliceForView(const model::Vec3& o, const model::Hemicube& grid, const SliceOptions& options) const;

  // rho(i, o) for the fixed light direction i (i.z < 0) over the camera hemisphere, at the cells
  // of o. Traced from the light side; used to check the reciprocity of the tracer itself.
  BtdfSlice SliceForLight(const model::Vec3& i, const model::Hemicube& grid, const SliceOptions& options) const;

 private:
  BtdfSlice TraceSlice(const model::Vec3& arrival, const model::Hemicube& grid, const SliceOptions& options) const;

  Slab slab_;
};

}  // namespace svbtdf::simulate
