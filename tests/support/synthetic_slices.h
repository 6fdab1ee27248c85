#pragma once
// Test support: BTDF slices synthesised from the dual-microfacet model with a known NDF, alpha,
// shadowing and scale, seen through the paper's rig geometry.
#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "svbtdf/fit/texel_fit.h"
#include "svbtdf/model/dual_microfacet.h"
#include "svbtdf/model/tabulated_ndf.h"

namespace svbtdf::fit {

// The paper's geometry around one texel at the origin: the camera 45 degrees from vertical in the
// x-z plane, a 40x40 dot grid on the monitor plane z = -d spanning 9.6 cm, centred on the
// straight-through point of the view ray. `offset` shifts the grid by a fraction of its pitch
// (0.5 gives the held-out directions between the fitted ones).
struct RigSamples {
  std::vector<model::Vec3> light;
  std::vector<double> solid_angle;
};

inline RigSamples DotGrid(const model::Vec3& view, int dots_per_side, double offset) {
  constexpr double kDepth = 0.04, kSpan = 0.096;
  const double pitch = kSpan / dots_per_side;
  const model::Vec3 centre = -view * (kDepth / view.z());
  RigSamples rig;
  for (int a = 0; a < dots_per_side; ++a) {
    for (int b = 0; b < dots_per_side; ++b) {
      const model::Vec3 p(centre.x() + (a + offset + 0.5 - 0.5 * dots_per_side) * pitch,
                   centre.y() + (b + offset + 0.5 - 0.5 * dots_per_side) * pitch, -kDepth);
      const double r2 = p.squaredNorm();
      const model::Vec3 i = p.normalized();
      rig.light.push_back(i);
      rig.solid_angle.push_back(pitch * pitch * std::abs(i.z()) / r2);
    }
  }
  return rig;
}

struct Truth {
  std::unique_ptr<model::TabulatedNdf> ndf;
  double eta = 1.5;
  double alpha = 0.3;
  double shadowing_roughness = 0.2;
  double k_s = 0.8;
  bool internal_reflection = false;  // the slab's T R R T paths in rho too (model/internal_reflection.h)

  double Rho(const model::Vec3& i, const model::Vec3& o) const {
    model::DualMicrofacetParams params;
    params.eta = eta;
    params.alpha = alpha;
    params.shadowing = model::SmithShadowing::Ggx(shadowing_roughness);
    params.internal_reflection = internal_reflection;
    return k_s * model::SpecularRho(*ndf, params, i, o);
  }
};

inline Truth MakeTruth(const model::Hemicube& grid, const model::Ndf& analytic, double alpha) {
  Truth truth;
  truth.ndf = std::make_unique<model::TabulatedNdf>(grid, analytic);
  truth.ndf->Normalize();
  truth.alpha = alpha;
  return truth;
}

inline TexelSlice Synthesize(const Truth& truth, const model::Vec3& view, const RigSamples& rig, double noise,
                      uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  TexelSlice slice;
  slice.view = view;
  slice.light = rig.light;
  slice.solid_angle = rig.solid_angle;
  for (const model::Vec3& i : rig.light) slice.rho.push_back(truth.Rho(i, view) * (1.0 + noise * gauss(rng)));
  return slice;
}

}  // namespace svbtdf::fit
