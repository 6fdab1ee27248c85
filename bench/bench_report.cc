// Cost and size of `svbtdf report` (report/) at the paper's scale: a 600 x 600-texel material
// (tests/support/paper_scale_material.h: 3,600 representatives, every texel a blend of 4) and its
// page: the time to write it on all cores and the bytes of every file, biggest first. Opening the
// page in a browser is timed by tools/report/browser_check.js on the folder it leaves (docs/report.md).
//
// Baseline (same process, same material): every texel's NDF blended once
// (fit::MaterialEvaluator::TexelCellD), the least a page of every texel would cost.
//
//   bench_report [SIDE] [OUT_DIR]   (defaults 600, a temporary folder that is removed)

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "bench_timing.h"
#include "paper_scale_material.h"
#include "svbtdf/common/parallel.h"
#include "svbtdf/report/material_report.h"

using svbtdf::bench::SecondsSince;

namespace {

using namespace svbtdf;
namespace fs = std::filesystem;

}  // namespace

int main(int argc, char** argv) {
  const int side = argc > 1 ? std::atoi(argv[1]) : 600;
  const bool keep = argc > 2;
  const fs::path folder = keep ? fs::path(argv[2]) : fs::temp_directory_path() / ("bench-report-" + std::to_string(::getpid()));
  fs::remove_all(folder);
  const fit::Material material = PaperScaleMaterial(side, std::max(1, side * side / 100));
  fit::WriteMaterial(folder / "material", material);

  const fit::MaterialEvaluator evaluator(material);
  std::atomic<double> checksum{0};
  auto start = std::chrono::steady_clock::now();
  common::ParallelFor(static_cast<int64_t>(side) * side, 0, 256, [&](int64_t begin, int64_t end) {
    double local = 0;
    for (int64_t t = begin; t < end; ++t) local += evaluator.TexelCellD(static_cast<int>(t % side), static_cast<int>(t / side))[100];
    checksum = checksum + local;
  });
  const double baseline = SecondsSince(start);

  report::MaterialReportOptions options;
  options.material_folder = (folder / "material").string();
  options.out = folder / "report";
  start = std::chrono::steady_clock::now();
  report::WriteMaterialReport(options);
  const double seconds = SecondsSince(start);

  std::vector<std::pair<uintmax_t, std::string>> files;
  uintmax_t total = 0;
  for (const auto& entry : fs::directory_iterator(options.out)) {
    files.emplace_back(entry.file_size(), entry.path().filename().string());
    total += entry.file_size();
  }
  std::sort(files.rbegin(), files.rend());
  std::printf("material %dx%d, %zu representatives (checksum %.3g)\n", side, side, material.representative_texels.size(), checksum.load());
  std::printf("baseline, every texel's NDF blended once: %.2f s\n", baseline);
  std::printf("report written:                           %.2f s (%.1fx the baseline)\n", seconds, seconds / baseline);
  std::printf("page: %.2f MB in %zu files; the largest:\n", total / 1e6, files.size());
  for (size_t k = 0; k < std::min<size_t>(8, files.size()); ++k) std::printf("  %9.3f MB  %s\n", files[k].first / 1e6, files[k].second.c_str());
  if (!keep) fs::remove_all(folder);
  return 0;
}
