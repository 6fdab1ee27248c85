// The C++ loop that bench/bench_python.py measures the Python module's Material.eval against:
// every (texel, wi, wo) pair of the files it wrote, evaluated one after the other on one thread
// with each texel's BTDF built beforehand (fit::MaterialEvaluator::Texel, as `svbtdf eval` and
// the module evaluate), the way a C++ program would loop over them.
//
//   bench_eval MATERIAL TEXELS.i64 WI.f64 WO.f64 REPEATS
// The files are raw little-endian arrays: N x 2 int64 (column, row), N x 3 float64 each.
// Prints one JSON line: {"pairs": N, "seconds": best of REPEATS, "cpu_seconds": the least CPU time of
// a repeat, "evaluations_per_s": pairs / seconds, "checksum": sum of every R}.

#include <chrono>
#include <ctime>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <optional>
#include <vector>

#include "bench_timing.h"
#include "svbtdf/fit/material.h"

using svbtdf::bench::SecondsSince;

namespace {

using namespace svbtdf;

template <typename T>
std::vector<T> ReadRaw(const char* path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  const std::streamsize bytes = in.tellg();
  std::vector<T> values(static_cast<size_t>(bytes) / sizeof(T));
  in.seekg(0);
  in.read(reinterpret_cast<char*>(values.data()), bytes);
  return values;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 6) {
    std::fprintf(stderr, "usage: bench_eval MATERIAL TEXELS.i64 WI.f64 WO.f64 REPEATS\n");
    return 2;
  }
  const fit::Material material = fit::ReadMaterial(argv[1]);
  const fit::MaterialEvaluator evaluator(material);
  const std::vector<int64_t> texels = ReadRaw<int64_t>(argv[2]);
  const std::vector<double> wi = ReadRaw<double>(argv[3]), wo = ReadRaw<double>(argv[4]);
  const size_t n = texels.size() / 2;
  std::vector<std::optional<fit::TexelBtdf>> built(static_cast<size_t>(material.width) * material.height);
  std::vector<const fit::TexelBtdf*> texel_of(n);
  for (size_t k = 0; k < n; ++k) {
    const int col = static_cast<int>(texels[2 * k]), row = static_cast<int>(texels[2 * k + 1]);
    std::optional<fit::TexelBtdf>& slot = built[static_cast<size_t>(row) * material.width + col];
    if (!slot) slot.emplace(evaluator.Texel(col, row));
    texel_of[k] = &*slot;
  }
  // Wall time and the CPU time of the same repeat: on a busy machine the CPU time is what the
  // loop cost, the wall time also what other processes took.
  double best = 1e300, best_cpu = 1e300, checksum = 0;
  for (int repeat = 0; repeat < std::atoi(argv[5]); ++repeat) {
    checksum = 0;
    const auto start = std::chrono::steady_clock::now();
    const std::clock_t cpu_start = std::clock();
    for (size_t k = 0; k < n; ++k) {
      const model::Vec3 i = model::Vec3(wi[3 * k], wi[3 * k + 1], wi[3 * k + 2]).normalized();
      const model::Vec3 o = model::Vec3(wo[3 * k], wo[3 * k + 1], wo[3 * k + 2]).normalized();
      const model::Rgb r = texel_of[k]->Evaluate(i, o);
      checksum += r[0] + r[1] + r[2];
    }
    best = std::min(best, SecondsSince(start));
    best_cpu = std::min(best_cpu, static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC);
  }
  std::printf("{\"pairs\": %zu, \"seconds\": %.6f, \"cpu_seconds\": %.6f, \"evaluations_per_s\": %.1f, "
              "\"checksum\": %.17g}\n", n, best, best_cpu, n / best, checksum);
  return 0;
}
