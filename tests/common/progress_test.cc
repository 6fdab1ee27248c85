// common/progress.h: the observer that the Python module's progress callback hangs on.

#include "svbtdf/common/progress.h"

#include <gtest/gtest.h>

#include <string>
#include <tuple>
#include <vector>

namespace svbtdf::common {
namespace {

using Report = std::tuple<std::string, int64_t, int64_t>;

TEST(ProgressObserver, HearsEveryBarEvenWhenBarsAreOffAndTheFinishedCount) {
  std::vector<Report> reports;
  ProgressBar::SetEnabled(false);
  ProgressBar::SetObserver([&](const std::string& label, int64_t done, int64_t total) {
    reports.emplace_back(label, done, total);
  });
  {
    ProgressBar bar("fitting", 10, "texels");
    bar.SkipAlreadyDone(3);
    bar.Advance(2);  // the first report comes at once, the next ones at most 10 times a second
    bar.Advance(5);
  }  // finishing reports the end, whatever the time
  ProgressBar::SetObserver({});
  ProgressBar::SetEnabled(true);
  ASSERT_GE(reports.size(), 2u);
  EXPECT_EQ(reports.front(), Report("fitting", 5, 10));  // resumed items count as done
  EXPECT_EQ(reports.back(), Report("fitting", 10, 10));

  ProgressBar after("unheard", 1);
  after.Advance();
  after.Finish();
  EXPECT_EQ(std::get<0>(reports.back()), "fitting");  // a removed observer hears nothing more
}

}  // namespace
}  // namespace svbtdf::common
