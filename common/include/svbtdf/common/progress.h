#pragma once
// A progress bar for long work: "label [#####.....] 512/1600 (32%) 41.2/s, 0:26 left".
// Draws on stderr only when it is a terminal (otherwise logs a line every few seconds), is
// thread safe (Advance() may be called from worker threads) and never slows the work it reports.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>

namespace svbtdf::common {

class ProgressBar {
 public:
  ProgressBar(std::string label, int64_t total, std::string unit = "items");
  ~ProgressBar();  // finishes the line
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  // Counts `n` more items done. Items resumed from a previous run should be passed to
  // SkipAlreadyDone() instead, so that the rate and time left reflect only new work.
  void Advance(int64_t n = 1);
  void SkipAlreadyDone(int64_t n);
  void Finish();

  // Globally silences all bars (tests, --quiet).
  static void SetEnabled(bool enabled);

  // A listener besides the terminal (the Python module's progress callback): every bar reports
  // (label, items done including resumed ones, total) to it at most 10 times a second and once
  // when it finishes, whether or not bars are drawn, from whichever thread advanced the bar. It
  // must not throw. An empty function removes it.
  using Observer = std::function<void(const std::string& label, int64_t done, int64_t total)>;
  static void SetObserver(Observer observer);

 private:
  void MaybeDraw(bool force);

  std::string label_;
  std::string unit_;
  int64_t total_;
  std::atomic<int64_t> done_{0};
  int64_t skipped_ = 0;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
  std::chrono::steady_clock::time_point last_report_;  // to the observer
  std::mutex draw_mutex_;
  bool finished_ = false;
  bool is_terminal_ = false;
};

}  // namespace svbtdf::common
