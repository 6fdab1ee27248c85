// Cost of clustering a processed store's slices (fit/clustering.h), the step of `svbtdf fit`
// that grows as the square of the texels (docs/benchmarks.md, "scaling.py").
//
// Baseline (same process, same slices): k-means comparing every texel with every centre on
// every pass (ClusteringOptions::exhaustive_assignment). Measured: the default, which skips the
// comparisons Hamerly's bounds rule out. Reports both times, the ratio, and whether the two
// gave the same clusters, representatives and weights (they must).
//
//   bench_cluster STORE [THREADS]   (STORE: a `svbtdf process` output; bench/scaling.py --keep)

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <vector>

#include "bench_timing.h"
#include "svbtdf/common/error.h"
#include "svbtdf/fit/clustering.h"
#include "svbtdf/fit/slice_store.h"

using svbtdf::bench::SecondsSince;

namespace {

using namespace svbtdf;

bool SameWeights(const std::vector<fit::AffineWeights>& a, const std::vector<fit::AffineWeights>& b) {
  if (a.size() != b.size()) return false;
  for (size_t t = 0; t < a.size(); ++t) {
    if (a[t].terms != b[t].terms) return false;
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_cluster STORE [THREADS]\n");
    return 2;
  }
  try {
    const fit::SliceStore store = fit::SliceStore::Open(argv[1]);
    // Every texel, as `svbtdf fit` clusters a store without masked texels.
    fit::SliceSource source;
    source.num_texels = store.geometry().num_texels();
    source.dimension = store.light_grid().num_cells();
    source.read = [&](int64_t t, float* out) { store.ReadSlice(t, out); };
    fit::ClusteringOptions options;
    options.threads = argc > 2 ? std::atoi(argv[2]) : 0;

    options.exhaustive_assignment = true;
    auto start = std::chrono::steady_clock::now();
    const fit::Clustering baseline = fit::ClusterSlices(source, options);
    const double baseline_seconds = SecondsSince(start);

    options.exhaustive_assignment = false;
    start = std::chrono::steady_clock::now();
    const fit::Clustering measured = fit::ClusterSlices(source, options);
    const double measured_seconds = SecondsSince(start);

    const bool same = baseline.representatives == measured.representatives && baseline.cluster == measured.cluster &&
                      SameWeights(baseline.weights, measured.weights);
    std::printf("texels clustered: %lld into %zu clusters (%d cells a slice)\n",
                static_cast<long long>(source.num_texels), measured.representatives.size(), source.dimension);
    std::printf("baseline, every texel against every centre: %.1f s\n", baseline_seconds);
    std::printf("measured, Hamerly's bounds:                 %.1f s\n", measured_seconds);
    std::printf("ratio baseline / measured:                  %.2f\n", baseline_seconds / measured_seconds);
    std::printf("same clusters, representatives and weights: %s\n", same ? "yes" : "NO");
    return same ? 0 : 1;
  } catch (const common::Error& e) {
    std::fprintf(stderr, "bench_cluster: %s\n", e.what());
    return 1;
  }
}
