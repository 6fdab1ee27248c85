// Processing cost and peak memory of `svbtdf process` on a simulated session.
//
// Baseline (same process): reading and decoding every image of the session once, the floor for
// any processing that reads its input. Measured: the whole ProcessSession (dark frames, flat
// field, rectification, HDR merge, measurement equation, diffuse separation, push-pull) with the
// true calibration. Reports both times, their ratio, and the process's peak resident memory.
//
//   svbtdf simulate --preset rice-paper --out SIM
//   bench_process SIM [THREADS] [TEXELS_X TEXELS_Y] [--keep STORE] [--no-baseline]
//
// --keep: the processed store is kept in STORE (a new folder) for a fit to time afterwards
// (bench/paper_scale.py), rather than removed. STORE may also be an unfinished store of the same
// settings, which is resumed.
// --no-baseline: the images are not read first; for profiling the processing alone, e.g. the
// diffuse separation and resampling of a kept store whose manifest was set back to unfinished
// ("complete": false; docs/benchmarks.md).

#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "bench_timing.h"
#include "svbtdf/common/error.h"
#include "svbtdf/session/session.h"
#include "svbtdf/process/process_session.h"
#include "truth_calibration.h"

using svbtdf::bench::SecondsSince;

namespace {

double PeakResidentMegabytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss / 1024.0;
}

}  // namespace

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  bool baseline_wanted = true;
  if (argc >= 2 && std::string(argv[argc - 1]) == "--no-baseline") {
    baseline_wanted = false;
    --argc;
  }
  fs::path keep;
  if (argc >= 3 && std::string(argv[argc - 2]) == "--keep") {
    keep = argv[argc - 1];
    argc -= 2;
  }
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_process SIMULATION_FOLDER [THREADS] [TEXELS_X TEXELS_Y] [--keep STORE] [--no-baseline]\n");
    return 2;
  }
  try {
    const fs::path simulation = argv[1];
    const svbtdf::session::Session session = svbtdf::session::Session::Open(simulation / "session");
    const svbtdf::calib::SessionCalibration calibration = svbtdf::CalibrationFromTruth(simulation);
    auto start = std::chrono::steady_clock::now();
    if (baseline_wanted) {
      for (const std::string& key : session.planned_keys()) session.ReadImage(key);
    }
    const double baseline = SecondsSince(start);
    const double baseline_peak = PeakResidentMegabytes();

    const fs::path out = keep.empty() ? simulation / ("bench-processed-" + std::to_string(::getpid())) : keep;
    svbtdf::process::ProcessOptions options;
    options.threads = argc > 2 ? std::atoi(argv[2]) : 0;
    if (argc > 4) {
      options.texels_x = std::atoi(argv[3]);
      options.texels_y = std::atoi(argv[4]);
    }
    start = std::chrono::steady_clock::now();
    const svbtdf::process::ProcessReport report = svbtdf::process::ProcessSession(session, calibration, out, options);
    const double measured = SecondsSince(start);
    std::printf("session: %zu images, %lld texels x %d dots\n", session.planned_keys().size(),
                static_cast<long long>(report.texels), report.dots);
    if (baseline_wanted) std::printf("baseline, read every image once:   %.1f s (peak %.0f MB)\n", baseline, baseline_peak);
    std::printf("process:                           %.1f s\n", measured);
    if (baseline_wanted) std::printf("ratio measured / baseline:         %.2f\n", measured / baseline);
    std::printf("peak resident memory:              %.0f MB\n", PeakResidentMegabytes());
    if (keep.empty()) fs::remove_all(out);
  } catch (const svbtdf::common::Error& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  }
  return 0;
}
