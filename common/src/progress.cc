#include "svbtdf/common/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <utility>

namespace svbtdf::common {
namespace {

std::atomic<bool> g_progress_enabled{true};

// The observer, if any; copied under the lock so that it can be replaced while bars report.
std::mutex g_observer_mutex;
ProgressBar::Observer g_observer;
std::atomic<bool> g_has_observer{false};

void Notify(const std::string& label, int64_t done, int64_t total) {
  ProgressBar::Observer observer;
  {
    std::lock_guard<std::mutex> lock(g_observer_mutex);
    observer = g_observer;
  }
  if (observer) observer(label, done, total);
}

std::string FormatDuration(double seconds) {
  if (!(seconds >= 0) || seconds > 359999) return "--:--";
  const int total = static_cast<int>(seconds + 0.5);
  char buffer[32];
  if (total >= 3600) {
    std::snprintf(buffer, sizeof buffer, "%d:%02d:%02d", total / 3600, (total / 60) % 60, total % 60);
  } else {
    std::snprintf(buffer, sizeof buffer, "%d:%02d", total / 60, total % 60);
  }
  return buffer;
}

}  // namespace

ProgressBar::ProgressBar(std::string label, int64_t total, std::string unit)
    : label_(std::move(label)),
      unit_(std::move(unit)),
      total_(std::max<int64_t>(total, 0)),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_ - std::chrono::hours(1)),
      last_report_(start_ - std::chrono::hours(1)),
      is_terminal_(::isatty(STDERR_FILENO) == 1) {}

ProgressBar::~ProgressBar() { Finish(); }

void ProgressBar::SetEnabled(bool enabled) { g_progress_enabled = enabled; }

void ProgressBar::SetObserver(Observer observer) {
  std::lock_guard<std::mutex> lock(g_observer_mutex);
  g_has_observer = static_cast<bool>(observer);
  g_observer = std::move(observer);
}

void ProgressBar::SkipAlreadyDone(int64_t n) {
  std::lock_guard<std::mutex> lock(draw_mutex_);
  skipped_ += n;
}

void ProgressBar::Advance(int64_t n) {
  done_.fetch_add(n, std::memory_order_relaxed);
  MaybeDraw(false);
}

void ProgressBar::Finish() {
  {
    std::lock_guard<std::mutex> lock(draw_mutex_);
    if (finished_) return;
  }
  MaybeDraw(true);
  std::lock_guard<std::mutex> lock(draw_mutex_);
  finished_ = true;
  if (g_progress_enabled && is_terminal_) std::fputc('\n', stderr);
}

void ProgressBar::MaybeDraw(bool force) {
  const bool observed = g_has_observer.load(std::memory_order_relaxed);
  if (!g_progress_enabled && !observed) return;
  const auto now = std::chrono::steady_clock::now();
  // A terminal is redrawn ~10 times a second; a log file gets a line every 5 seconds.
  const auto interval = is_terminal_ ? std::chrono::milliseconds(100) : std::chrono::milliseconds(5000);
  std::unique_lock<std::mutex> lock(draw_mutex_, std::try_to_lock);
  if (!lock.owns_lock() || finished_) return;
  const int64_t fresh = done_.load(std::memory_order_relaxed);
  const int64_t done = std::min(fresh + skipped_, total_ > 0 ? total_ : fresh + skipped_);
  if (observed && (force || now - last_report_ >= std::chrono::milliseconds(100))) {
    last_report_ = now;
    Notify(label_, done, total_);
  }
  if (!g_progress_enabled) return;
  if (!force && now - last_draw_ < interval) return;
  last_draw_ = now;

  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double rate = elapsed > 0 ? fresh / elapsed : 0.0;
  const double left = rate > 0 ? (total_ - done) / rate : -1.0;
  const double fraction = total_ > 0 ? static_cast<double>(done) / total_ : 0.0;

  constexpr int kWidth = 28;
  const int filled = static_cast<int>(fraction * kWidth);
  std::string bar(filled, '#');
  bar.append(kWidth - filled, '.');
  char line[512];
  std::snprintf(line, sizeof line, "%s [%s] %lld/%lld %s (%3.0f%%) %.1f/s, %s left, %s elapsed",
                label_.c_str(), bar.c_str(), static_cast<long long>(done),
                static_cast<long long>(total_), unit_.c_str(), 100.0 * fraction, rate,
                FormatDuration(left).c_str(), FormatDuration(elapsed).c_str());
  if (is_terminal_) {
    std::fprintf(stderr, "\r\033[K%s", line);
  } else {
    std::fprintf(stderr, "%s\n", line);
  }
  std::fflush(stderr);
}

}  // namespace svbtdf::common
