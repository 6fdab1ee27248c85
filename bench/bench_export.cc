// Cost of `svbtdf export` (export/) at the scale issue 17 names: a 600 x 600-texel dual-microfacet
// material (tests/support/paper_scale_material.h: 3,600 representatives, GGX tables at NDF
// resolution 32, every texel a blend of 4) fitted texel by texel with GGX lobes and written as
// glTF, on all cores.
//
// Baseline (same process, same material): every texel's NDF evaluated once, the blend of its
// representatives' tables at every cell (fit::MaterialEvaluator::TexelCellD), which the lobe fit
// starts from. Reports both, the ratio, and the fit's error distribution.
//
//   bench_export [SIDE] [OUT_DIR]   (defaults 600, a temporary folder that is removed)

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "bench_timing.h"
#include "paper_scale_material.h"
#include "svbtdf/common/parallel.h"
#include "svbtdf/export/gltf.h"
#include "svbtdf/export/lobe_fit.h"

using svbtdf::bench::SecondsSince;

namespace {

using namespace svbtdf;

double BlendEveryTexelSeconds(const fit::Material& material) {
  const fit::MaterialEvaluator evaluator(material);
  std::atomic<double> checksum{0};  // keeps the work from being optimised away
  const auto start = std::chrono::steady_clock::now();
  common::ParallelFor(static_cast<int64_t>(material.width) * material.height, 0, 256, [&](int64_t begin, int64_t end) {
    double local = 0;
    for (int64_t t = begin; t < end; ++t) {
      local += evaluator.TexelCellD(static_cast<int>(t % material.width), static_cast<int>(t / material.width))[100];
    }
    checksum = checksum + local;
  });
  const double seconds = SecondsSince(start);
  std::printf("  (checksum %.3g)\n", checksum.load());
  return seconds;
}

}  // namespace

int main(int argc, char** argv) {
  const int side = argc > 1 ? std::atoi(argv[1]) : 600;
  const bool keep = argc > 2;
  const std::filesystem::path out =
      keep ? std::filesystem::path(argv[2])
           : std::filesystem::temp_directory_path() / ("svbtdf-bench-export-" + std::to_string(::getpid()));
  auto start = std::chrono::steady_clock::now();
  const fit::Material material = PaperScaleMaterial(side, side * side / 100);
  std::printf("%d x %d material with %d representatives built in %.1f s\n", side, side, side * side / 100, SecondsSince(start));

  const double baseline = BlendEveryTexelSeconds(material);
  start = std::chrono::steady_clock::now();
  const exporter::MaterialLobes lobes = exporter::FitMaterialLobes(material, 0);
  const double fit_seconds = SecondsSince(start);
  exporter::WriteGltf(material, lobes, out, "bench");
  const double measured = SecondsSince(start);
  if (!keep) std::filesystem::remove_all(out);

  const exporter::ErrorDistribution error = exporter::Distribution(lobes.relative_error);
  std::printf("threads: %d\n", common::ThreadCount(0));
  std::printf("baseline: every texel's NDF blended once: %.2f s\n", baseline);
  std::printf("measured: lobe fit %.2f s, whole export (fit + glTF, PNGs, maps) %.2f s\n", fit_seconds, measured);
  std::printf("ratio lobe fit / baseline: %.2f; export / baseline: %.2f\n", fit_seconds / baseline, measured / baseline);
  std::printf("lobe fit relative error: median %.4f, p90 %.4f, max %.4f\n", error.median, error.p90, error.max);
  return 0;
}
