#pragma once
// The Ceres set-up of the fit's small per-texel problems (a handful of parameters, a few hundred
// residuals): dense Levenberg-Marquardt on one thread, since the texels themselves are what runs
// in parallel, and silent, since thousands of them run.

#include <ceres/ceres.h>

namespace svbtdf::fit {

inline ceres::Solver::Options SmallProblemOptions(int max_iterations) {
  ceres::Solver::Options options;
  options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = max_iterations;
  options.logging_type = ceres::SILENT;
  options.num_threads = 1;
  return options;
}

}  // namespace svbtdf::fit
