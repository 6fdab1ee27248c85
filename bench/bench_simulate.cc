// Cost of the simulator's dot images at paper scale: `grid-sheet` (600x600 texels, 40x40 dots),
// the images `svbtdf simulate --preset grid-sheet` spends most of its time on (docs/benchmarks.md,
// "Simulation").
//
// A sample of the preset's dots spread over the whole grid (every k-th, wrapping around) is rendered as the
// simulation renders it (RenderDot: the truth material integrated over the dot's disk for every
// pixel group) and exposed at every bracket of the plan (Expose: shot and read noise,
// quantisation). Baseline (same process, same images): the exposures alone, whose cost does not
// depend on the material or the quadrature, so the ratio render / exposure compares commits on a
// noisy machine. The checksum (FNV-1a of every exposed pixel) says whether a change left the
// images bit-identical.
//
//   bench_simulate [DOTS] [THREADS]   (default 40 dots, all cores)

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#include "bench_timing.h"
#include "svbtdf/common/parallel.h"
#include "svbtdf/simulate/capture_render.h"
#include "svbtdf/simulate/presets.h"

using svbtdf::bench::SecondsSince;

namespace {

using namespace svbtdf;

uint64_t Fnv1a(const std::vector<uint16_t>& pixels, uint64_t hash) {
  for (const uint16_t v : pixels) {
    hash = (hash ^ (v & 0xff)) * 0x100000001b3ULL;
    hash = (hash ^ (v >> 8)) * 0x100000001b3ULL;
  }
  return hash;
}

}  // namespace

int main(int argc, char** argv) {
  const int sample = std::max(1, argc > 1 ? std::atoi(argv[1]) : 40);
  const int threads = common::ThreadCount(argc > 2 ? std::atoi(argv[2]) : 0);

  auto start = std::chrono::steady_clock::now();
  const auto setup = simulate::MakeSimulatedSetup(simulate::MakePreset("grid-sheet"), 1, threads, {});
  const double setup_s = SecondsSince(start);
  const simulate::RigRenderer& renderer = *setup->renderer;
  const std::vector<simulate::Dot>& dots = setup->rig->dots();
  const std::vector<double>& exposures = setup->plan.dot_exposures_s;

  const int count = std::min<int>(sample, static_cast<int>(dots.size()));
  // A stride one more than the grid's spacing walks the grid diagonally: every row and column.
  const size_t stride = dots.size() / count + 1;
  double render_s = 0.0, expose_s = 0.0;
  uint64_t checksum = 0xcbf29ce484222325ULL;
  common::FloatImage radiance;
  for (int n = 0; n < count; ++n) {
    const int q = static_cast<int>((static_cast<size_t>(n) * stride) % dots.size());
    start = std::chrono::steady_clock::now();
    renderer.RenderDot(dots[q], &radiance);
    render_s += SecondsSince(start);
    for (size_t b = 0; b < exposures.size(); ++b) {
      start = std::chrono::steady_clock::now();
      const common::CameraImage image =
          renderer.Expose(radiance, exposures[b], setup->seed, simulate::NoiseStream("dots", q, static_cast<int>(b)));
      expose_s += SecondsSince(start);
      checksum = Fnv1a(image.pixels, checksum);
    }
  }
  const double per_dot = (render_s + expose_s) / count;
  const double per_exposure = expose_s / (count * static_cast<double>(exposures.size()));

  std::printf("grid-sheet: %zu dots, %zu exposures each, %d threads; setup %.1f s\n", dots.size(), exposures.size(),
              threads, setup_s);
  std::printf("dots rendered:                       %d (every %zu-th, modulo %zu)\n", count, stride, dots.size());
  std::printf("baseline, one exposure:              %.3f s\n", per_exposure);
  std::printf("one dot's radiance image:            %.3f s\n", render_s / count);
  std::printf("ratio radiance / exposure:           %.2f\n", render_s / count / per_exposure);
  std::printf("one dot, rendered and exposed:       %.3f s\n", per_dot);
  std::printf("%zu dots at this rate:               %.1f min\n", dots.size(), dots.size() * per_dot / 60.0);
  std::printf("checksum of the exposed images:      %016llx\n", static_cast<unsigned long long>(checksum));
  return 0;
}
