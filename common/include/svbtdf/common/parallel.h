#pragma once
// The one parallel loop of the project: work-stealing chunks of an index range on a few threads.

#include <cstdint>
#include <functional>

namespace svbtdf::common {

inline constexpr int kMaxThreads = 1024;

// `requested` threads, or every hardware thread when requested <= 0. Throws
// svbtdf::Error(kInvalidInput) naming --threads beyond kMaxThreads.
int ThreadCount(int requested);

// Runs body(begin, end) over [0, n) in chunks of `chunk` indices taken in order by ThreadCount(threads)
// threads (the caller's thread is one of them). The first exception thrown by a body stops the
// other threads at their next chunk and is rethrown here.
void ParallelFor(int64_t n, int threads, int64_t chunk, const std::function<void(int64_t, int64_t)>& body);

}  // namespace svbtdf::common
