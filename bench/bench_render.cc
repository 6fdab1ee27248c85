// Cost of `svbtdf render` (render/renderer.h) at the scale issue 16 names: a 512 x 512 image at
// 64 samples per pixel of the background scene, seen from 25 degrees, of a synthetic 600 x
// 600-texel dual-microfacet material (3,600 representatives, 1%, GGX tables of roughness
// 0.1-0.4 at the paper's NDF resolution 32; every texel an affine blend of 4 of them).
//
// Baseline (same process, same material): the same number of BSDF samples (texel BSDF built and
// sampled, no camera, no scene) in a tight loop on all threads. Reports both, the ratio and the
// rate.
//
//   bench_render [RESOLUTION] [SPP]   (defaults 512, 64)

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>

#include "bench_timing.h"
#include "paper_scale_material.h"
#include "svbtdf/common/parallel.h"
#include "svbtdf/common/random.h"
#include "svbtdf/model/ggx.h"
#include "svbtdf/render/renderer.h"

using svbtdf::bench::SecondsSince;

namespace {

using namespace svbtdf;

// The baseline: `samples` BSDF samples at random texels and views, spread over the threads.
double TightLoopSeconds(const render::Surface& surface, int64_t samples) {
  std::atomic<int64_t> kept{0};
  const auto start = std::chrono::steady_clock::now();
  constexpr int64_t kChunk = 1 << 14;
  common::ParallelFor((samples + kChunk - 1) / kChunk, 0, 1, [&](int64_t begin, int64_t end) {
    render::BsdfScratch scratch;
    for (int64_t chunk = begin; chunk < end; ++chunk) {
      common::Pcg32 rng(7, static_cast<uint64_t>(chunk));
      int64_t local = 0;
      for (int64_t k = 0; k < kChunk; ++k) {
        const int col = static_cast<int>(rng.NextDouble() * surface.texels_x());
        const int row = static_cast<int>(rng.NextDouble() * surface.texels_y());
        const model::Vec3 wo = model::SphericalDirection(0.44 * rng.NextDouble(), model::kTwoPi * rng.NextDouble());
        const model::Bsdf& bsdf = surface.At(col, row, scratch);
        if (bsdf.Sample(wo, rng.NextDouble(), {rng.NextDouble(), rng.NextDouble()})) ++local;
      }
      kept += local;
    }
  });
  const double seconds = SecondsSince(start);
  std::printf("  (%lld of the baseline's samples carried light)\n", static_cast<long long>(kept.load()));
  return seconds;
}

}  // namespace

int main(int argc, char** argv) {
  const int resolution = argc > 1 ? std::atoi(argv[1]) : 512;
  const int spp = argc > 2 ? std::atoi(argv[2]) : 64;
  auto start = std::chrono::steady_clock::now();
  const fit::Material material = PaperScaleMaterial(600, 3600);
  const render::MaterialSurface surface(material, material.width_m, material.height_m, "synthetic material");
  std::printf("600 x 600 material with 3,600 representatives built in %.1f s\n", SecondsSince(start));

  render::RenderOptions options;
  options.camera.width = options.camera.height = resolution;
  options.camera.theta_deg = 25;
  options.camera.distance_m = 0.25;
  options.camera.fov_deg = 20;
  options.samples_per_pixel = spp;
  options.progress = false;
  const render::BackgroundScene scene = render::BackgroundScene::Checkerboard(0.05, 0.01);
  const int64_t samples = static_cast<int64_t>(resolution) * resolution * spp;

  // Both runs first build the representatives' sampling tables (lazily, once): a short warm-up
  // render keeps that out of either measurement.
  options.camera.width = options.camera.height = 64;
  render::Render(surface, scene, options);
  options.camera.width = options.camera.height = resolution;

  const double baseline = TightLoopSeconds(surface, samples);
  start = std::chrono::steady_clock::now();
  render::Render(surface, scene, options);
  const double measured = SecondsSince(start);
  std::printf("threads: %d\n", common::ThreadCount(0));
  std::printf("baseline: %lld BSDF samples in a tight loop: %.1f s (%.2f M/s)\n", static_cast<long long>(samples),
              baseline, samples / baseline * 1e-6);
  std::printf("measured: %d x %d render at %d spp: %.1f s (%.2f M samples/s)\n", resolution, resolution, spp, measured,
              samples / measured * 1e-6);
  std::printf("ratio render / tight loop: %.2f\n", measured / baseline);
  return 0;
}
