// GoldenSectionSearch (common/src/minimize.cc): the minimum of a unimodal function to within the
// tolerance, at an interior point or an end of the interval, in one new evaluation per step
// (2 + ceil(log_phi(range / tolerance)) evaluations).
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "svbtdf/common/minimize.h"

namespace svbtdf::common {
namespace {

const double kPhi = (1.0 + std::sqrt(5.0)) / 2.0;

// The evaluations golden-section search needs: two to start, then one per shrink by 1/phi.
int ExpectedEvaluations(double range, double tolerance) {
  return 2 + static_cast<int>(std::ceil(std::log(range / tolerance) / std::log(kPhi)));
}

struct Counted {
  std::function<double(double)> f;
  int evaluations = 0;
  std::function<double(double)> Wrapped() {
    return [this](double x) {
      ++evaluations;
      return f(x);
    };
  }
};

TEST(GoldenSectionSearch, FindsTheMinimumOfUnimodalFunctionsWithinTheTolerance) {
  struct Case {
    const char* name;
    std::function<double(double)> f;
    double lo, hi, minimum;
    // Near a minimum of value v a function changes by about f''/2 dx^2, invisible below
    // eps |v|: cos and x log x (v ~ -1) cannot be told apart closer than ~1e-8 of theirs.
    double finest_tolerance = 1e-9;
  };
  const Case cases[] = {
      {"parabola", [](double x) { return (x - 0.3) * (x - 0.3); }, 0.0, 1.0, 0.3},
      {"kink", [](double x) { return std::abs(x - 0.7); }, 0.0, 1.0, 0.7},
      {"asymmetric", [](double x) { return x < 2.5 ? 3.0 * (2.5 - x) : (x - 2.5) * (x - 2.5); }, -4.0, 10.0, 2.5},
      {"cosine", [](double x) { return std::cos(x); }, 2.0, 4.5, M_PI, 1e-6},
      {"quartic", [](double x) { return std::pow(x + 1.25, 4); }, -3.0, 0.0, -1.25},
      {"x log x", [](double x) { return x * std::log(x); }, 0.05, 1.0, std::exp(-1.0), 1e-6},
  };
  for (const Case& c : cases) {
    for (double tolerance : {1e-3, 1e-6, 1e-9}) {
      if (tolerance < c.finest_tolerance) continue;
      const double x = GoldenSectionSearch(c.f, c.lo, c.hi, tolerance);
      // The final interval, narrower than `tolerance`, brackets the minimum; its midpoint is
      // within half of it. (The flat quartic is bracketed too: only comparisons are used.)
      EXPECT_LE(std::abs(x - c.minimum), 0.5 * tolerance + 1e-12) << c.name << " tolerance " << tolerance;
    }
  }
}

TEST(GoldenSectionSearch, FindsAMinimumAtEitherEndOfTheInterval) {
  const double tolerance = 1e-6;
  EXPECT_NEAR(GoldenSectionSearch([](double x) { return x; }, 0.0, 1.0, tolerance), 0.0, tolerance);
  EXPECT_NEAR(GoldenSectionSearch([](double x) { return -x; }, 0.0, 1.0, tolerance), 1.0, tolerance);
  EXPECT_NEAR(GoldenSectionSearch([](double x) { return std::exp(x); }, -2.0, 3.0, tolerance), -2.0, tolerance);
  EXPECT_NEAR(GoldenSectionSearch([](double x) { return (x - 9.0) * (x - 9.0); }, 1.0, 5.0, tolerance), 5.0,
              tolerance);
}

TEST(GoldenSectionSearch, ATolerancePastTheIntervalReturnsItsMiddleAfterTwoEvaluations) {
  Counted f{[](double x) { return (x - 0.9) * (x - 0.9); }};
  EXPECT_DOUBLE_EQ(GoldenSectionSearch(f.Wrapped(), 0.0, 1.0, 2.0), 0.5);
  EXPECT_EQ(f.evaluations, 2);
}

TEST(GoldenSectionSearch, EvaluationsGrowWithTheLogarithmOfRangeOverTolerance) {
  for (double range : {1.0, 50.0}) {
    for (double tolerance : {1e-2, 1e-5, 1e-8, 1e-11}) {
      Counted f{[range](double x) { return (x - 0.37 * range) * (x - 0.37 * range); }};
      GoldenSectionSearch(f.Wrapped(), 0.0, range, tolerance);
      const int expected = ExpectedEvaluations(range, tolerance);
      // Rounding can move the last comparison of width against tolerance by one step.
      EXPECT_GE(f.evaluations, expected - 1) << "range " << range << " tolerance " << tolerance;
      EXPECT_LE(f.evaluations, expected + 1) << "range " << range << " tolerance " << tolerance;
    }
  }
  // A thousand times finer costs log_phi(1000) = 14.4 more evaluations, not a thousand times more.
  Counted coarse{[](double x) { return x * x; }}, fine{[](double x) { return x * x; }};
  GoldenSectionSearch(coarse.Wrapped(), -1.0, 1.0, 1e-3);
  GoldenSectionSearch(fine.Wrapped(), -1.0, 1.0, 1e-6);
  EXPECT_GE(fine.evaluations - coarse.evaluations, 13);
  EXPECT_LE(fine.evaluations - coarse.evaluations, 16);
}

}  // namespace
}  // namespace svbtdf::common
