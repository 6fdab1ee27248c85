// Cost of refining the texels after clustering (fit/refine_texels.h) at the paper's density of
// dots (40x40) and NDF resolution (32), on a synthetic 48x48-texel store fitted with 1%
// representatives.
//
// Baseline (same process, same material): the refinement on one thread. Measured: on all
// threads, as `svbtdf fit` runs it. Reports milliseconds per texel, the ratio, the refinement's
// cost next to one representative's full fit, and what 360,000 texels (600 x 600) take here.
// Then what the standard errors and the model-error term (RefineOptions::uncertainty) add to the
// measured refinement: both settings timed twice, alternately, the faster of each pair kept
// (issue 20 asks for at most 20%).
//
//   bench_refine [TEXELS_PER_SIDE]   (default 48)

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <numeric>
#include <string>
#include <unistd.h>

#include "analytic_store.h"
#include "bench_timing.h"
#include "svbtdf/common/parallel.h"
#include "svbtdf/fit/fit_material.h"
#include "svbtdf/fit/refine_texels.h"

using svbtdf::bench::SecondsSince;

namespace {

using namespace svbtdf;
using namespace svbtdf::fit;

double SecondsPerTexel(const SliceStore& store, const Material& fitted, int threads, bool uncertainty = true) {
  Material material = fitted;
  std::vector<int64_t> texels(static_cast<size_t>(material.width) * material.height);
  std::iota(texels.begin(), texels.end(), 0);
  RefineOptions options;
  options.threads = threads;
  options.uncertainty = uncertainty;
  const auto start = std::chrono::steady_clock::now();
  RefineTexels(store, {}, texels, options, &material);
  return SecondsSince(start) / static_cast<double>(texels.size());
}

}  // namespace

int main(int argc, char** argv) {
  const int side = argc > 1 ? std::atoi(argv[1]) : 48;
  const std::filesystem::path folder =
      std::filesystem::temp_directory_path() / ("svbtdf-bench-refine-" + std::to_string(::getpid()));
  testing::AnalyticMaterial truth;
  truth.width = truth.height = side;
  testing::WriteAnalyticStore(folder, truth, 40, 0.01);
  const SliceStore store = SliceStore::Open(folder);
  FitMaterialOptions options;
  options.representative_fraction = 0.01;
  options.refine_texels = false;
  options.progress = false;
  const Material fitted = FitMaterial(store, options);
  const double fit_per_representative =
      fitted.provenance.at("statistics").at("seconds_per_fit").get<double>();

  const double baseline = SecondsPerTexel(store, fitted, 1);
  const int threads = common::ThreadCount(0);
  const double measured = SecondsPerTexel(store, fitted, threads);
  const double without = std::min(SecondsPerTexel(store, fitted, threads, false), SecondsPerTexel(store, fitted, threads, false));
  const double with = std::min(measured, SecondsPerTexel(store, fitted, threads));
  std::filesystem::remove_all(folder);

  std::printf("texels refined: %d (%dx%d, 1%% representatives, 32x32 NDF hemicube, 1600 dots)\n", side * side, side,
              side);
  std::printf("baseline, 1 thread:                  %.2f ms per texel\n", 1e3 * baseline);
  std::printf("%d threads (wall):                    %.2f ms per texel\n", threads, 1e3 * measured);
  std::printf("ratio baseline / measured:           %.2f\n", baseline / measured);
  std::printf("one representative's fit (wall):     %.0f times one texel's refinement\n", fit_per_representative / measured);
  std::printf("360,000 texels at this rate:         %.1f min\n", 360000 * measured / 60.0);
  std::printf("without the standard errors:         %.2f ms per texel; they add %+.1f%%\n", 1e3 * without,
              100.0 * (with / without - 1.0));
  return 0;
}
