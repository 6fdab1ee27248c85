// ParallelFor and ThreadCount (common/src/parallel.cc): every index of [0, n) is handed out
// exactly once in chunks of at most `chunk` on at most ThreadCount(threads) threads; the first
// exception thrown by a body is rethrown on the caller's thread and no new chunk starts after it.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <memory>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "svbtdf/common/error.h"
#include "svbtdf/common/parallel.h"

namespace svbtdf::common {
namespace {

TEST(ThreadCount, ARequestIsTakenAsIsAndZeroMeansEveryHardwareThread) {
  EXPECT_EQ(ThreadCount(1), 1);
  EXPECT_EQ(ThreadCount(7), 7);
  const int all = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  EXPECT_EQ(ThreadCount(0), all);
  EXPECT_EQ(ThreadCount(-3), all);
  EXPECT_EQ(ThreadCount(kMaxThreads), kMaxThreads);
}

// `fit --threads 1000000` aborted under a memory limit (issue 15): now one line naming --threads.
TEST(ThreadCount, RefusesAbsurdRequestsNamingTheOption) {
  try {
    ThreadCount(1000000);
    FAIL() << "a million threads were accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kInvalidInput);
    EXPECT_NE(std::string(e.what()).find("--threads"), std::string::npos) << e.what();
  }
}

// (n, threads, chunk)
class ParallelForCoverage : public ::testing::TestWithParam<std::tuple<int64_t, int, int64_t>> {};

TEST_P(ParallelForCoverage, VisitsEveryIndexExactlyOnceInChunksOfAtMostChunk) {
  // Named copies, not a structured binding: Clang 14 (the checked build) cannot capture
  // structured bindings in a lambda.
  const int64_t n = std::get<0>(GetParam());
  const int threads = std::get<1>(GetParam());
  const int64_t chunk = std::get<2>(GetParam());
  std::vector<std::atomic<int>> visits(static_cast<size_t>(std::max<int64_t>(n, 0)));
  std::mutex mutex;
  std::set<std::thread::id> workers;
  std::atomic<int> calls{0}, bad_ranges{0};
  ParallelFor(n, threads, chunk, [&](int64_t begin, int64_t end) {
    ++calls;
    if (begin < 0 || end > n || begin >= end || end - begin > std::max<int64_t>(chunk, 1)) {
      ++bad_ranges;
      return;
    }
    for (int64_t i = begin; i < end; ++i) ++visits[static_cast<size_t>(i)];
    std::lock_guard<std::mutex> lock(mutex);
    workers.insert(std::this_thread::get_id());
  });
  EXPECT_EQ(bad_ranges.load(), 0);
  for (int64_t i = 0; i < n; ++i) ASSERT_EQ(visits[static_cast<size_t>(i)].load(), 1) << "index " << i;
  const int64_t step = std::max<int64_t>(chunk, 1);
  const int64_t chunks = n <= 0 ? 0 : (n + step - 1) / step;
  EXPECT_EQ(calls.load(), chunks);  // every chunk but the last is full
  EXPECT_LE(static_cast<int64_t>(workers.size()), std::min<int64_t>(ThreadCount(threads), chunks));
}

INSTANTIATE_TEST_SUITE_P(
    Combinations, ParallelForCoverage,
    ::testing::Values(std::make_tuple(int64_t{0}, 4, int64_t{8}),     // nothing to do: no call
                      std::make_tuple(int64_t{-5}, 2, int64_t{1}),    // a negative range is empty
                      std::make_tuple(int64_t{1}, 4, int64_t{1}),     // n < threads
                      std::make_tuple(int64_t{3}, 8, int64_t{1}),     // n < threads
                      std::make_tuple(int64_t{5}, 3, int64_t{100}),   // chunk > n: one chunk
                      std::make_tuple(int64_t{1000}, 1, int64_t{7}),  // one thread, ragged last chunk
                      std::make_tuple(int64_t{1000}, 4, int64_t{1}),
                      std::make_tuple(int64_t{1001}, 3, int64_t{10}),
                      std::make_tuple(int64_t{100000}, 2, int64_t{64}),
                      std::make_tuple(int64_t{17}, 4, int64_t{0})));  // chunk <= 0 is taken as 1

TEST(ParallelFor, OneThreadRunsTheChunksInOrderOnTheCallersThread) {
  std::vector<int64_t> begins;
  const std::thread::id caller = std::this_thread::get_id();
  bool elsewhere = false;
  ParallelFor(10, 1, 3, [&](int64_t begin, int64_t end) {
    begins.push_back(begin);
    EXPECT_EQ(end, std::min<int64_t>(begin + 3, 10));
    if (std::this_thread::get_id() != caller) elsewhere = true;
  });
  EXPECT_EQ(begins, (std::vector<int64_t>{0, 3, 6, 9}));
  EXPECT_FALSE(elsewhere);
}

TEST(ParallelFor, OnOneThreadTheFirstThrowIsRethrownAndNothingRunsAfterIt) {
  std::vector<int64_t> begins;
  try {
    ParallelFor(100, 1, 1, [&](int64_t begin, int64_t) {
      begins.push_back(begin);
      if (begin == 3) throw std::runtime_error("first at 3");
      if (begin == 7) throw std::runtime_error("second at 7");
    });
    FAIL() << "the exception was swallowed";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "first at 3");
  }
  EXPECT_EQ(begins, (std::vector<int64_t>{0, 1, 2, 3}));
}

// Every body throws: exactly one of them is rethrown (as itself), and the loop stops early.
TEST(ParallelFor, WhenEveryChunkThrowsOneOfThemIsRethrown) {
  constexpr int64_t kN = 10000;
  std::atomic<int64_t> calls{0};
  try {
    ParallelFor(kN, 4, 1, [&](int64_t begin, int64_t) {
      ++calls;
      std::this_thread::sleep_for(std::chrono::microseconds(200));
      throw std::out_of_range("chunk " + std::to_string(begin));
    });
    FAIL() << "the exception was swallowed";
  } catch (const std::out_of_range& e) {
    EXPECT_EQ(std::string(e.what()).rfind("chunk ", 0), 0u) << e.what();
  }
  // Each thread stops at its first throw: at most one chunk per thread.
  EXPECT_LE(calls.load(), 4);
  EXPECT_GE(calls.load(), 1);
}

// After one body throws, the other threads finish the chunk they hold and take no new one.
TEST(ParallelFor, StopsHandingOutWorkAfterAThrow) {
  constexpr int64_t kN = 100000;
  constexpr int64_t kThrowAt = 20;
  std::atomic<int64_t> calls{0};
  EXPECT_THROW(ParallelFor(kN, 3, 1,
                           [&](int64_t begin, int64_t) {
                             ++calls;
                             std::this_thread::sleep_for(std::chrono::microseconds(200));
                             if (begin == kThrowAt) throw std::runtime_error("stop");
                           }),
               std::runtime_error);
  // Without the stop the loop would make 100000 calls (20 s); with it, the chunks before the
  // throw plus whatever the other two threads took while it unwound (a handful; 1000 is slack
  // for a loaded machine, 0.2 s of their work).
  EXPECT_GT(calls.load(), kThrowAt);
  EXPECT_LT(calls.load(), 1000);
}

// An svbtdf::Error thrown on a worker thread reaches the caller with its kind and parts.
TEST(ParallelFor, AnErrorFromAWorkerThreadKeepsItsKind) {
  const std::thread::id caller = std::this_thread::get_id();
  std::atomic<bool> thrown{false};
  try {
    ParallelFor(200, 4, 1, [&](int64_t, int64_t) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));  // lets the workers take chunks
      if (std::this_thread::get_id() != caller && !thrown.exchange(true)) {
        throw Error(ErrorKind::kNumerical, "texel 12", "did not converge", "lower the tolerance");
      }
    });
    FAIL() << "no worker thread threw (or the error was swallowed)";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kNumerical);
    EXPECT_EQ(e.subject(), "texel 12");
    EXPECT_STREQ(e.what(), "texel 12: did not converge (lower the tolerance)");
  }
  EXPECT_TRUE(thrown.load());
}

}  // namespace
}  // namespace svbtdf::common
