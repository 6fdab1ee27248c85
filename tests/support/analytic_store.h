#pragma once
// Test support: a processed session (slice store) synthesised from a known dual-microfacet
// material, without images. The rig is the paper's: the camera 1 m from the sample centre,
// 45 degrees above it on the -y side; the monitor 4 cm behind the 8 cm sample; a square grid of
// dots 1.2 times the sample's width, centred on where the view ray through the sample centre
// meets the monitor. Every texel's GGX roughness and blend weight alpha vary smoothly (linearly)
// across the sample, so that clustering has something to interpolate.
#include <cmath>
#include <filesystem>
#include <random>
#include <vector>

#include "svbtdf/calib/session_calibration.h"
#include "svbtdf/fit/slice_store.h"
#include "svbtdf/process/slice_store_writer.h"
#include "svbtdf/model/dual_microfacet.h"
#include "svbtdf/model/ggx.h"

namespace svbtdf::testing {

struct AnalyticMaterial {
  int width = 16, height = 16;
  double eta = 1.5;

  // Texel (x, y): u, v in [0, 1] across the sample.
  double U(int x) const { return width > 1 ? x / (width - 1.0) : 0.5; }
  double V(int y) const { return height > 1 ? y / (height - 1.0) : 0.5; }
  bool rough = false;  // rice-paper-like lobes: GGX 0.25-0.45 across, 1.1-1.6x that along
  // When both are > 0, every texel's lobe instead: GGX `across` along x, `along` along y.
  double across = 0.0, along = 0.0;
  bool internal_reflection = false;  // the slab's T R R T paths in R too (DualMicrofacetParams)

  model::GgxNdf Ndf(int x, int y) const {
    if (across > 0 && along > 0) return model::GgxNdf(across, along);
    if (rough) {
      const double across = 0.25 + 0.20 * U(x);
      return model::GgxNdf(across, across * (1.1 + 0.5 * V(y)));
    }
    return model::GgxNdf(0.18 + 0.10 * U(x), 0.16 + 0.06 * V(y));
  }
  model::DualMicrofacetParams Params(int x, int y) const {
    model::DualMicrofacetParams p;
    p.eta = eta;
    p.alpha = 0.3 + 0.2 * U(x) + 0.2 * V(y);
    p.shadowing = model::SmithShadowing::Ggx(0.2);
    const double scale = 0.8 + 0.1 * V(y);
    p.k_s = {scale, 0.95 * scale, 0.9 * scale};
    p.rho_d = {0.0, 0.0, 0.0};
    p.internal_reflection = internal_reflection;
    return p;
  }
  model::Rgb R(int x, int y, const model::Vec3& i, const model::Vec3& o) const { return model::EvaluateMaterial(Ndf(x, y), Params(x, y), i, o); }
};

// The hand-made calibration of the rig above (only the geometry matters to the store).
inline calib::SessionCalibration AnalyticCalibration(int dots_per_side) {
  constexpr double kSample = 0.08, kDepth = 0.04, kCamera = 1.0;
  const double theta = model::kPi / 4;
  const model::Vec3 camera(0.0, -kCamera * std::sin(theta), kCamera * std::cos(theta));
  calib::SessionCalibration c;
  // A plausible camera: the store only keeps it, the geometry below is what the fit uses.
  c.camera.camera.width = 640;
  c.camera.camera.height = 480;
  c.camera.camera.fx = c.camera.camera.fy = 2000.0;
  c.camera.camera.cx = 320.0;
  c.camera.camera.cy = 240.0;
  c.sample_plane.rotation = Eigen::Matrix3d::Identity();
  c.sample_plane.translation = -camera;  // CameraCentre() = -R^T t = camera
  c.sample_plane.width_m = c.sample_plane.height_m = kSample;
  c.monitor.distance_m = kDepth;
  const double span = 1.2 * kSample, pitch = span / dots_per_side;
  const double centre_y = kDepth * std::tan(theta);  // the view ray through the centre, continued
  for (int row = 0; row < dots_per_side; ++row) {
    for (int col = 0; col < dots_per_side; ++col) {
      calib::DotPosition dot;
      dot.position = model::Vec3(-0.5 * span + (col + 0.5) * pitch, centre_y - 0.5 * span + (row + 0.5) * pitch, -kDepth);
      dot.monitor_px = {static_cast<double>(col), static_cast<double>(row)};
      c.monitor.dots.push_back(dot);
    }
  }
  return c;
}

// Writes PROCESSED/ at `folder` with R of `truth` at every texel and dot, times (1 + noise N(0,1)).
// `store_eta` is what the store records as the sample's nominal eta (0: unknown).
inline void WriteAnalyticStore(const std::filesystem::path& folder, const AnalyticMaterial& truth, int dots_per_side,
                               double noise, double store_eta = 1.5, uint64_t seed = 7, int tile_texels = 1024) {
  const calib::SessionCalibration calibration = AnalyticCalibration(dots_per_side);
  fit::SliceStoreInfo info;
  info.texels_x = truth.width;
  info.texels_y = truth.height;
  info.num_dots = static_cast<int>(calibration.monitor.dots.size());
  info.eta = store_eta;
  info.tile_texels = tile_texels;
  const fit::TexelGeometry geometry = process::MakeTexelGeometry(calibration, truth.width, truth.height);
  process::SliceStoreWriter writer(folder, info, calibration);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::vector<float> rgb(3 * geometry.num_texels());
  for (int q = 0; q < info.num_dots; ++q) {
    for (int64_t t = 0; t < geometry.num_texels(); ++t) {
      const int x = static_cast<int>(t % truth.width), y = static_cast<int>(t / truth.width);
      const model::Rgb r = truth.R(x, y, geometry.Light(t, q), geometry.View(t));
      const double factor = 1.0 + noise * gauss(rng);
      for (int c = 0; c < 3; ++c) rgb[3 * t + c] = static_cast<float>(r[c] * factor);
    }
    writer.WriteDot(q, rgb);
  }
  process::SliceStoreWriter::FinishOptions finish;
  finish.progress = false;
  writer.Finish(finish);
}

}  // namespace svbtdf::testing
