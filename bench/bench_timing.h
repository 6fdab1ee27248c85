#pragma once
// Wall-clock timing shared by the benchmarks (each reports ratios of these within one run).

#include <chrono>

namespace svbtdf::bench {

// Seconds elapsed since `start`, by the monotonic clock.
inline double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace svbtdf::bench
