#include "svbtdf/common/parallel.h"

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <thread>
#include <string>
#include <vector>

#include "svbtdf/common/error.h"

namespace svbtdf::common {

int ThreadCount(int requested) {
  // A million threads aborted `fit` under a memory limit (issue 15): far beyond any machine's
  // cores, each thread's stack alone exhausts memory.
  if (requested > kMaxThreads) {
    ThrowInvalidInput("--threads", std::to_string(requested) + " threads asked for; at most " + std::to_string(kMaxThreads));
  }
  if (requested > 0) return requested;
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

void ParallelFor(int64_t n, int threads, int64_t chunk, const std::function<void(int64_t, int64_t)>& body) {
  if (n <= 0) return;
  chunk = std::max<int64_t>(chunk, 1);
  const int workers = static_cast<int>(std::min<int64_t>(ThreadCount(threads), (n + chunk - 1) / chunk));
  std::atomic<int64_t> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto work = [&] {
    try {
      for (;;) {
        const int64_t begin = next.fetch_add(chunk);
        if (begin >= n) return;
        body(begin, std::min(n, begin + chunk));
      }
    } catch (...) {
      std::lock_guard<std::mutex> lock(error_mutex);
      if (!error) error = std::current_exception();
      next = n;  // the others stop at their next chunk
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < workers; ++t) pool.emplace_back(work);
  work();
  for (std::thread& thread : pool) thread.join();
  if (error) std::rethrow_exception(error);
}

}  // namespace svbtdf::common
