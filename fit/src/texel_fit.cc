#include "svbtdf/fit/texel_fit.h"

#include <ceres/ceres.h>

#include <Eigen/IterativeLinearSolvers>
#include <iostream>  // Eigen/MetisSupport reports METIS's errors on std::cerr without including it
#include <Eigen/MetisSupport>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <functional>
#include <mutex>
#include <optional>
#include <string>

#include "svbtdf/common/error.h"
#include "svbtdf/common/minimize.h"
#include "svbtdf/fit/ndf_error.h"
#include "svbtdf/fit/quality.h"
#include "svbtdf/model/dual_microfacet.h"
#include "svbtdf/model/internal_reflection.h"
#include "svbtdf/model/tabulated_ndf.h"
#include "small_problem.h"
#include "uncertainty.h"

namespace svbtdf::fit {

using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;
using Triplet = Eigen::Triplet<double, int>;

// ------------------------------------------------------------------------------------------------
// The data-independent part of the ln D system.

struct TexelFitter::GridSystem {
  std::vector<int> column;  // unknown index of each cell, -1 for the fixed horizon cells
  int num_unknowns = 0;
  // Normal-equation blocks of the smoothness rows and of the symmetry rows (already weighted),
  // and their right-hand sides (the fixed horizon values moved across).
  SparseMatrix smoothness_normal;
  Eigen::VectorXd smoothness_rhs;
  SparseMatrix symmetry_normal;
};

namespace {

struct Sample {
  model::Vec3 light;
  double rho = 0.0;
  double weight = 1.0;
  double solid_angle = 1.0;
  bool used = false;  // bright enough for the log-space rows
};

struct SparseRows {
  std::vector<Triplet> triplets;
  std::vector<double> rhs;
  int rows = 0;
};

// Accumulates coefficient * ln D(h) into `row`, moving fixed horizon values to the right side.
void AddInterpolatedTerm(const model::Hemicube& grid, const std::vector<int>& column, double horizon_ln_d,
                         const model::Vec3& h, double coefficient, int row, SparseRows* rows) {
  for (const auto& [cell, weight] : grid.Interpolation(h)) {
    if (weight == 0.0) continue;
    const int col = column[cell];
    if (col < 0) {
      rows->rhs[row] -= coefficient * weight * horizon_ln_d;
    } else {
      rows->triplets.emplace_back(row, col, coefficient * weight);
    }
  }
}

SparseMatrix NormalMatrix(const SparseRows& rows, int num_unknowns, Eigen::VectorXd* normal_rhs) {
  SparseMatrix a(rows.rows, num_unknowns);
  a.setFromTriplets(rows.triplets.begin(), rows.triplets.end());
  const Eigen::Map<const Eigen::VectorXd> b(rows.rhs.data(), rows.rows);
  *normal_rhs = a.transpose() * b;
  return SparseMatrix(a.transpose() * a);
}

// Golden-section search that also considers the interval's ends: alpha = 0 or 1 (one rough side
// only) are legitimate answers that an interior search only approaches.
double MinimumIncludingEnds(const std::function<double(double)>& f, double lo, double hi, double tolerance) {
  double best_x = common::GoldenSectionSearch(f, lo, hi, tolerance), best_f = f(best_x);
  for (const double x : {lo, hi}) {
    const double fx = f(x);
    if (fx < best_f) best_f = fx, best_x = x;
  }
  return best_x;
}

// The next alpha of the alternations from g(alpha), the alpha search's answer for the current
// one: a secant step on g(alpha) - alpha = 0 through the last two alternations, or g's own answer
// (a plain step) where the secant is not to be trusted: at the first alternation, where the two
// alphas are too close for g's search tolerance to leave a slope, and where g's slope is near 1.
// There the criterion barely tells one alpha from another once D follows it (the texels whose
// lobe the dot grid cuts: slopes of 0.93-0.96 at the edge of `small`'s session), the fixed point
// moves by 1 / (1 - slope) times any error in g, and extrapolating towards it replaces the plain
// steps' pull towards the start by an answer the data do not support.
class AlphaFixedPoint {
 public:
  // `secant` false: plain steps only, the paper's iteration.
  explicit AlphaFixedPoint(bool secant) : secant_(secant) {}

  // The alpha to try next, given the current `alpha` and the search's answer `g` for it.
  double Next(double alpha, double g) {
    double next = g;
    if (secant_ && previous_ && std::abs(alpha - previous_->alpha) > kMinSecantBase) {
      const double slope = (g - previous_->g) / (alpha - previous_->alpha);
      // 1 / (1 - slope): the sum of the plain steps still to come, were g linear.
      if (slope <= kMaxSlope) next = std::clamp(alpha + (g - alpha) / (1.0 - slope), 0.0, 1.0);
    }
    previous_ = Alternation{alpha, g};
    return next;
  }

 private:
  static constexpr double kMinSecantBase = 1e-3;  // ten times the alpha search's tolerance
  static constexpr double kMaxSlope = 0.75;        // at most 4 plain steps' worth
  struct Alternation {
    double alpha, g;
  };
  bool secant_;
  std::optional<Alternation> previous_;
};

}  // namespace

// ------------------------------------------------------------------------------------------------

// METIS's nested dissection orders the ln D system for less fill than AMD: the data rows couple
// each sample's entry and exit half-vector cells, far apart on the hemicube, and L holds 312,000
// entries against AMD's 401,000 (32x32 cells, 1,600 dots), so each factorisation takes 0.6 times
// as long and each solve 0.8 times. Its analysis takes 22 ms to AMD's 7, once per pattern: each
// texel of a real session has its own, as it sees the sample from its own view, and an ordering
// kept from one view fills in twice as much at a view 2 degrees away (measured, 2026-12-06).
using Ldlt = Eigen::SimplicialLDLT<SparseMatrix, Eigen::Lower, Eigen::MetisOrdering<int>>;

namespace {

// The factorisation P^T L D L^T P of the last factorised system with L's entries in single
// precision, applied as the conjugate gradients' preconditioner. A back-substitution reads all of
// L twice (312,000 entries at 32 x 32 cells and 1,600 dots, more than a core's 2 MiB cache) and
// was a third of a representative's fit; in single precision it reads two thirds of the bytes.
// The preconditioner stays symmetric positive definite (any unit lower L' with D > 0), so the
// conjugate gradients still converge to their tolerance, at most an iteration or two later.
class SinglePrecisionFactor {
 public:
  // After every factorisation of `factor` (its index arrays are read in place).
  void Refresh(const Ldlt& factor) {
    const SparseMatrix& l = factor.matrixL().nestedExpression();
    size_ = l.cols();
    outer_ = l.outerIndexPtr();
    inner_ = l.innerIndexPtr();
    values_.assign(l.valuePtr(), l.valuePtr() + l.nonZeros());
    inverse_d_ = factor.vectorD().cwiseInverse();
    p_ = factor.permutationP();
    p_inverse_ = factor.permutationPinv();
  }

  Eigen::VectorXd Solve(const Eigen::VectorXd& b) const {
    Eigen::VectorXd x = p_ * b;
    for (Eigen::Index j = 0; j < size_; ++j) {  // L y = P b, column by column (L unit lower)
      const double xj = x[j];
      if (xj == 0.0) continue;
      for (int k = outer_[j]; k < outer_[j + 1]; ++k) x[inner_[k]] -= static_cast<double>(values_[k]) * xj;
    }
    x.array() *= inverse_d_.array();
    for (Eigen::Index j = size_; j-- > 0;) {  // L^T z = D^-1 y, by L's columns as rows of L^T
      double sum = x[j];
      for (int k = outer_[j]; k < outer_[j + 1]; ++k) sum -= static_cast<double>(values_[k]) * x[inner_[k]];
      x[j] = sum;
    }
    return p_inverse_ * x;
  }

 private:
  Eigen::Index size_ = 0;
  const int* outer_ = nullptr;
  const int* inner_ = nullptr;
  std::vector<float> values_;
  Eigen::VectorXd inverse_d_;
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> p_, p_inverse_;
};

// A preconditioner for Eigen's ConjugateGradient that applies the factorisation of a nearby
// matrix: the ln D system of the previous alpha (or of the previous texel of the same view). The
// systems differ only in the data rows' weights, so a few iterations replace a factorisation.
class FactorPreconditioner {
 public:
  void set_factor(const SinglePrecisionFactor* factor) { factor_ = factor; }
  template <typename Matrix>
  FactorPreconditioner& analyzePattern(const Matrix&) { return *this; }
  template <typename Matrix>
  FactorPreconditioner& factorize(const Matrix&) { return *this; }
  template <typename Matrix>
  FactorPreconditioner& compute(const Matrix&) { return *this; }
  template <typename Rhs>
  Eigen::VectorXd solve(const Rhs& b) const { return factor_->Solve(b); }
  Eigen::ComputationInfo info() const { return Eigen::Success; }

 private:
  const SinglePrecisionFactor* factor_ = nullptr;
};

}  // namespace

struct FitWorkspace::State {
  Ldlt solver;
  SinglePrecisionFactor preconditioner;  // `solver`'s factor, refreshed with it
  bool factorized = false;        // `solver` holds a factorisation of the analysed pattern
  std::vector<int> outer, inner;  // the pattern the solver was analysed for
  int64_t factorizations = 0;
  int64_t symbolic_analyses = 0;
  int64_t iterative_solves = 0;
};

FitWorkspace::FitWorkspace() : state_(std::make_unique<State>()) {}
FitWorkspace::~FitWorkspace() = default;
FitWorkspace::FitWorkspace(FitWorkspace&&) noexcept = default;
FitWorkspace& FitWorkspace::operator=(FitWorkspace&&) noexcept = default;
int64_t FitWorkspace::factorizations() const { return state_->factorizations; }
int64_t FitWorkspace::symbolic_analyses() const { return state_->symbolic_analyses; }
int64_t FitWorkspace::iterative_solves() const { return state_->iterative_solves; }

namespace {

// Conjugate gradients preconditioned by the last factorisation stop here: the relative residual
// |b - N x| / |b| of a direct solve is ~1e-14, and ln D moves by less than 1e-9 between the two
// (tests/fit/texel_fit_test.cc). A system the old factor no longer fits is factorised afresh.
constexpr double kIterativeTolerance = 1e-9;
constexpr int kMaxIterations = 40;

// Solves N x = b, starting from `guess` (empty: zero): by conjugate gradients preconditioned with
// the workspace's factorisation when it has one of N's pattern, else (or when they do not
// converge) by factorising N, reusing the symbolic analysis when the pattern is the last one's.
Eigen::VectorXd SolveNormalEquations(const SparseMatrix& normal, const Eigen::VectorXd& rhs,
                                     const Eigen::VectorXd& guess, bool iterative, FitWorkspace::State* state) {
  const int n = static_cast<int>(normal.cols());
  const int nnz = static_cast<int>(normal.nonZeros());
  const bool same_pattern =
      static_cast<int>(state->outer.size()) == n + 1 && static_cast<int>(state->inner.size()) == nnz &&
      std::equal(state->outer.begin(), state->outer.end(), normal.outerIndexPtr()) &&
      std::equal(state->inner.begin(), state->inner.end(), normal.innerIndexPtr());
  if (iterative && same_pattern && state->factorized) {
    Eigen::ConjugateGradient<SparseMatrix, Eigen::Lower | Eigen::Upper, FactorPreconditioner> cg;
    cg.preconditioner().set_factor(&state->preconditioner);
    cg.setTolerance(kIterativeTolerance);
    cg.setMaxIterations(kMaxIterations);
    cg.compute(normal);
    const Eigen::VectorXd x = cg.solveWithGuess(rhs, guess.size() == n ? guess : Eigen::VectorXd::Zero(n));
    if (cg.info() == Eigen::Success && x.allFinite()) {
      ++state->iterative_solves;
      return x;
    }
  }
  if (!same_pattern) {
    {
      // METIS draws from one random number generator for the whole process, reseeded at each
      // call: two threads ordering at once would race on it and order differently run to run.
      static std::mutex metis;
      const std::lock_guard<std::mutex> lock(metis);
      state->solver.analyzePattern(normal);
    }
    state->outer.assign(normal.outerIndexPtr(), normal.outerIndexPtr() + n + 1);
    state->inner.assign(normal.innerIndexPtr(), normal.innerIndexPtr() + nnz);
    ++state->symbolic_analyses;
  }
  state->solver.factorize(normal);
  ++state->factorizations;
  state->factorized = state->solver.info() == Eigen::Success;
  if (state->factorized) state->preconditioner.Refresh(state->solver);
  if (!state->factorized) {
    throw common::Error(common::ErrorKind::kNumerical, "NDF solve", "the normal equations are singular",
                "increase the smoothness weight");
  }
  return state->solver.solve(rhs);
}

}  // namespace

// ------------------------------------------------------------------------------------------------

TexelFitter::TexelFitter(double eta, const TexelFitOptions& options)
    : eta_(eta), options_(options), grid_(options.ndf_resolution) {
  model::DualMicrofacetModel validate_eta(eta);  // throws for eta <= 1
  if (!(options.smoothness_weight > 0)) {
    common::ThrowInvalidInput("smoothness weight", "must be > 0 (it keeps cells without data determined)");
  }
  if (!(options.alpha_tolerance > 0) || options.max_alternations < 1) {
    common::ThrowInvalidInput("alpha search", "needs a positive tolerance and at least one alternation");
  }
  system_ = BuildGridSystem(options.free_horizon);
  // The paper's fixed horizon, for the free-horizon fits whose scale escapes (Fit).
  if (options.free_horizon) fixed_horizon_system_ = BuildGridSystem(false);
}

std::shared_ptr<const TexelFitter::GridSystem> TexelFitter::BuildGridSystem(bool free_horizon) const {
  const TexelFitOptions& options = options_;
  auto system = std::make_shared<GridSystem>();
  const int cells = grid_.num_cells();
  system->column.assign(cells, -1);
  for (int c = 0; c < cells; ++c) {
    if (free_horizon || !grid_.IsHorizon(c)) system->column[c] = system->num_unknowns++;
  }
  const int n = system->num_unknowns;

  SparseRows smooth;
  for (int c = 0; c < cells; ++c) {
    const int col = system->column[c];
    if (col < 0) continue;
    const int row = smooth.rows++;
    smooth.rhs.push_back(0.0);
    int neighbours = 0;
    for (const int nb : grid_.Neighbours(c)) {
      if (nb < 0) continue;
      ++neighbours;
      if (system->column[nb] < 0) {
        smooth.rhs[row] += options.smoothness_weight * options.horizon_ln_d;
      } else {
        smooth.triplets.emplace_back(row, system->column[nb], -options.smoothness_weight);
      }
    }
    smooth.triplets.emplace_back(row, col, options.smoothness_weight * neighbours);
  }
  system->smoothness_normal = NormalMatrix(smooth, n, &system->smoothness_rhs);

  SparseRows symmetry;
  for (int c = 0; c < cells; ++c) {
    const int mirror = grid_.MirroredCell(c);
    const int col = system->column[c], mirror_col = system->column[mirror];
    if (col < 0 || mirror_col < 0 || mirror <= c) continue;  // each pair once
    const int row = symmetry.rows++;
    symmetry.rhs.push_back(0.0);
    symmetry.triplets.emplace_back(row, col, options.symmetry_weight);
    symmetry.triplets.emplace_back(row, mirror_col, -options.symmetry_weight);
  }
  Eigen::VectorXd unused_rhs;
  system->symmetry_normal = NormalMatrix(symmetry, n, &unused_rhs);
  return system;
}

namespace {

std::vector<Sample> PrepareSamples(const TexelSlice& slice, double dark_fraction) {
  const size_t n = slice.light.size();
  const auto size_error = [](const char* what) {
    common::ThrowInvalidInput("texel slice", std::string(what) + " has a different length than the light directions");
  };
  if (slice.rho.size() != n) size_error("rho");
  if (!slice.solid_angle.empty() && slice.solid_angle.size() != n) size_error("solid_angle");
  if (!slice.weight.empty() && slice.weight.size() != n) size_error("weight");
  if (!slice.rho_rgb.empty() && slice.rho_rgb.size() != n) size_error("rho_rgb");
  if (!(slice.view.z() > 0) || std::abs(slice.view.norm() - 1) > 1e-6) {
    common::ThrowInvalidInput("texel slice", "the view direction must be a unit vector with z > 0");
  }
  std::vector<Sample> samples(n);
  double brightest = 0.0;
  for (size_t k = 0; k < n; ++k) {
    Sample& s = samples[k];
    s.light = slice.light[k];
    s.rho = slice.rho[k];
    s.weight = slice.weight.empty() ? 1.0 : slice.weight[k];
    s.solid_angle = slice.solid_angle.empty() ? 1.0 : slice.solid_angle[k];
    if (!(s.light.z() < 0) || std::abs(s.light.norm() - 1) > 1e-6) {
      common::ThrowInvalidInput("texel slice", "light direction " + std::to_string(k) + " is not a unit vector with z < 0");
    }
    if (!std::isfinite(s.rho) || !std::isfinite(s.weight) || s.weight < 0) {
      common::ThrowInvalidInput("texel slice", "sample " + std::to_string(k) + " has a non-finite value or negative weight");
    }
    if (s.weight > 0) brightest = std::max(brightest, s.rho);
  }
  for (Sample& s : samples) s.used = s.weight > 0 && s.rho > 0 && s.rho >= dark_fraction * brightest;
  return samples;
}

// Mean incident direction weighted by rho times solid angle (paper eq. 18).
template <typename RhoOf>
model::Vec3 WeightedMeanDirection(const std::vector<Sample>& samples, RhoOf rho_of) {
  model::Vec3 sum = model::Vec3::Zero();
  double total = 0.0;
  for (size_t k = 0; k < samples.size(); ++k) {
    if (samples[k].weight <= 0) continue;
    const double w = rho_of(k) * samples[k].solid_angle;
    sum += w * samples[k].light;
    total += w;
  }
  return total > 0 ? model::Vec3(sum / total) : model::Vec3::Zero();
}

}  // namespace

namespace {

model::SmithShadowing ShadowingFor(double roughness) {
  return roughness > 0 ? model::SmithShadowing::Ggx(roughness) : model::SmithShadowing::None();
}

// The two virtual configurations of every sample, without D.
struct Configurations {
  std::vector<model::VirtualConfiguration> entry, exit;
};

Configurations ComputeConfigurations(const model::DualMicrofacetModel& btdf, const std::vector<Sample>& samples,
                                     const model::Vec3& view) {
  Configurations c;
  c.entry.reserve(samples.size());
  c.exit.reserve(samples.size());
  for (const Sample& s : samples) {
    c.entry.push_back(btdf.RoughEntry(s.light, view));
    c.exit.push_back(btdf.RoughExit(s.light, view));
  }
  return c;
}

// Does the blend with this alpha have a finite logarithm for this sample's configurations?
bool RowDefined(const model::VirtualConfiguration& entry, const model::VirtualConfiguration& exit, double alpha) {
  if (alpha >= 1.0) return entry.valid && entry.factor > 0;
  if (alpha <= 0.0) return exit.valid && exit.factor > 0;
  return entry.valid && exit.valid && entry.factor > 0 && exit.factor > 0;
}

// Per-sample model values for a fixed D: rho_T and rho_B.
void EvaluateConfigurations(const model::Ndf& ndf, const Configurations& configs, std::vector<double>* rho_t,
                            std::vector<double>* rho_b) {
  const size_t n = configs.entry.size();
  rho_t->assign(n, 0.0);
  rho_b->assign(n, 0.0);
  for (size_t k = 0; k < n; ++k) {
    if (configs.entry[k].valid) (*rho_t)[k] = configs.entry[k].factor * ndf.D(configs.entry[k].h);
    if (configs.exit[k].valid) (*rho_b)[k] = configs.exit[k].factor * ndf.D(configs.exit[k].h);
  }
}

// Log residuals of the fitted model for Ceres: the shadowing roughness and ln k_s are free.
struct ShadowingResidual {
  const std::vector<Sample>* samples;
  const std::vector<int>* rows;  // indices of the samples used
  const model::TabulatedNdf* ndf;
  model::Vec3 view;
  double eta;
  double alpha;

  bool operator()(double const* const* parameters, double* residuals) const {
    const double roughness = parameters[0][0];
    const double ln_k = parameters[0][1];
    if (!(roughness > 0)) return false;
    const model::DualMicrofacetModel btdf(eta, model::SmithShadowing::Ggx(roughness));
    for (size_t j = 0; j < rows->size(); ++j) {
      const Sample& s = (*samples)[(*rows)[j]];
      const double rho = btdf.Rho(*ndf, alpha, s.light, view);
      if (!(rho > 0)) return false;
      residuals[j] = std::sqrt(s.weight) * (std::log(rho) + ln_k - std::log(s.rho));
    }
    return true;
  }
};

// The profile of one more parameter over the final ln D pass. That pass's data rows are
// w_r (alpha ln f_T + (1 - alpha) ln f_B + [ln D terms] - ln rho); with the parameter free too its
// Jacobian is [A g], g_r the rows' derivative in the parameter. The parameter's variance with D
// free is s^2 / (g^T g - u^T N^-1 u), u = A^T g (the Schur complement of the pass's normal matrix
// N, still factorised: one more back-substitution), and D moves with it by dx/dp = -N^-1 u. Built
// once per texel for every parameter whose profile is taken (alpha's, the shadowing roughness's).
class FinalPassProfile {
 public:
  using Solve = std::function<Eigen::VectorXd(const Eigen::VectorXd&)>;
  // `data_ssr` over `data_rows`: the pass's data residuals, for s^2 (two more parameters than
  // the table: the profiled one and the scale).
  FinalPassProfile(const SparseRows& data, int num_unknowns, double data_ssr, int data_rows, Solve solve_final)
      : a_(data.rows, num_unknowns), s2_(data_ssr / std::max(1, data_rows - 2)), solve_final_(std::move(solve_final)) {
    a_.setFromTriplets(data.triplets.begin(), data.triplets.end());
  }

  int rows() const { return static_cast<int>(a_.rows()); }

  struct Result {
    double variance = -1;       // -1: the data do not pin the parameter down
    Eigen::VectorXd n_inv_u;    // N^-1 u: minus D's move per unit of the parameter
  };
  Result Of(const Eigen::VectorXd& g) const {
    Result result;
    const Eigen::VectorXd u = a_.transpose() * g;
    result.n_inv_u = solve_final_(u);
    const double schur = g.squaredNorm() - u.dot(result.n_inv_u);
    if (schur > 0 && s2_ > 0) result.variance = s2_ / schur;
    return result;
  }

 private:
  SparseMatrix a_;
  double s2_;
  Solve solve_final_;
};

// The final pass's rows' derivative in the shadowing roughness: the configurations' factors f
// carry G, so g_r = w_r d/dr (alpha ln f_T + (1 - alpha) ln f_B), by central differences.
Eigen::VectorXd ShadowingRowGradient(const std::vector<Sample>& samples, const model::Vec3& view, double eta,
                                     double alpha, double roughness, const std::vector<int>& row_sample) {
  const double step = 1e-4 * std::max(roughness, 0.05);
  const auto configurations = [&](double r) {
    return ComputeConfigurations(model::DualMicrofacetModel(eta, ShadowingFor(r)), samples, view);
  };
  const Configurations above = configurations(roughness + step), below = configurations(roughness - step);
  const auto ln_factor = [](const model::VirtualConfiguration& c) { return c.valid && c.factor > 0 ? std::log(c.factor) : 0.0; };
  Eigen::VectorXd g = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(row_sample.size()));
  for (size_t r = 0; r < row_sample.size(); ++r) {
    const int k = row_sample[r];
    if (!samples[k].used || !(samples[k].weight > 0)) continue;
    const double up = alpha * ln_factor(above.entry[k]) + (1 - alpha) * ln_factor(above.exit[k]);
    const double down = alpha * ln_factor(below.entry[k]) + (1 - alpha) * ln_factor(below.exit[k]);
    g[r] = std::sqrt(samples[k].weight) * (up - down) / (2 * step);
  }
  return g;
}

// The relative RMSE and log RMS of `fitted` over the slice's samples, and the per-channel scales
// k_s_rgb of its shape (the model with k_s = 1, `fitted` / result->k_s).
void MeasureResiduals(const TexelSlice& slice, const std::vector<Sample>& samples, const FittedTexel& fitted,
                      TexelFitResult* result) {
  const model::Vec3& view = slice.view;
  double squared_error = 0, squared_rho = 0, squared_log = 0, model_squared = 0;
  std::array<double, 3> model_dot_rgb = {0, 0, 0};
  result->samples_used = 0;
  for (size_t k = 0; k < samples.size(); ++k) {
    const Sample& s = samples[k];
    if (s.weight <= 0) continue;
    const double predicted = fitted.Rho(s.light, view);
    squared_error += model::Square(predicted - s.rho);
    squared_rho += model::Square(s.rho);
    if (s.used && predicted > 0) {
      squared_log += model::Square(std::log(predicted) - std::log(s.rho));
      ++result->samples_used;
    }
    if (!slice.rho_rgb.empty()) {
      const double shape = predicted / result->k_s;
      model_squared += shape * shape;
      for (int c = 0; c < 3; ++c) model_dot_rgb[c] += shape * slice.rho_rgb[k][c];
    }
  }
  result->relative_rmse = squared_rho > 0 ? std::sqrt(squared_error / squared_rho) : 0.0;
  result->log_rms = result->samples_used > 0 ? std::sqrt(squared_log / result->samples_used) : 0.0;
  for (int c = 0; c < 3; ++c) {
    result->k_s_rgb[c] = slice.rho_rgb.empty() || model_squared <= 0 ? result->k_s : model_dot_rgb[c] / model_squared;
  }
}

}  // namespace

TexelFitResult TexelFitter::Fit(const TexelSlice& slice, FitWorkspace* workspace) const {
  const GridSystem* system = system_.get();
  TexelFitResult result = FitDualTermsOrFixHorizon(slice, &system, workspace);
  if (!options_.internal_reflection) return result;
  // The term is small beside the direct paths (a few percent of rho), so a fit that ignores it
  // is a close start, and each refit moves D, alpha and k_s a little less.
  for (int pass = 0; pass < options_.internal_reflection_passes; ++pass) {
    const model::TabulatedNdf ndf(grid_, result.ln_d);
    result = FitDualTermsOrFixHorizon(WithoutInternalReflection(slice, ndf, eta_, result.alpha, result.k_s, result.k_s_rgb),
                                      &system, workspace);
  }
  // Residuals and channel scales against what was measured, the term included.
  MeasureResiduals(slice, PrepareSamples(slice, options_.dark_fraction), Model(result), &result);
  return result;
}

TexelFitResult TexelFitter::FitDualTermsOrFixHorizon(const TexelSlice& slice, const GridSystem** system,
                                                     FitWorkspace* workspace) const {
  TexelFitResult result = FitDualTerms(slice, **system, workspace);
  // A free horizon lets the table's mass escape into cells no dot looks at; the normalisation then
  // shrinks D where the dots do look and k_s grows to make up for it (k_s of 1e4-1e12 on a Monte
  // Carlo slab truth, docs/validation.md). The paper's fixed horizon pins that mass, and the
  // texel keeps it for the rest of its fit.
  if (*system != fixed_horizon_system_.get() && fixed_horizon_system_ && !(result.k_s <= kMaxPlausibleKs)) {
    *system = fixed_horizon_system_.get();
    result = FitDualTerms(slice, **system, workspace);
  }
  result.horizon_fixed_instead = *system == fixed_horizon_system_.get();
  return result;
}

TexelSlice WithoutInternalReflection(const TexelSlice& slice, const model::Ndf& ndf, double eta, double alpha,
                                     double k_s, const std::array<double, 3>& k_s_rgb) {
  const model::InternalReflection paths(eta);
  TexelSlice remaining = slice;
  for (size_t k = 0; k < slice.light.size(); ++k) {
    const double term = paths.Blend(ndf, alpha, slice.light[k], slice.view);
    remaining.rho[k] -= k_s * term;
    for (int c = 0; c < 3; ++c) {
      if (k < remaining.rho_rgb.size()) remaining.rho_rgb[k][c] -= k_s_rgb[c] * term;
      if (k < remaining.measured_rgb.size()) remaining.measured_rgb[k][c] -= k_s_rgb[c] * term;
    }
  }
  return remaining;
}

TexelFitResult TexelFitter::FitDualTerms(const TexelSlice& slice, const GridSystem& system,
                                         FitWorkspace* workspace) const {
  FitWorkspace local_workspace;
  FitWorkspace::State* state = (workspace ? workspace : &local_workspace)->state_.get();
  const std::vector<Sample> samples = PrepareSamples(slice, options_.dark_fraction);
  const model::Vec3& view = slice.view;
  const int used = static_cast<int>(std::count_if(samples.begin(), samples.end(), [](const Sample& s) { return s.used; }));
  if (used < 8) {
    throw common::Error(common::ErrorKind::kNumerical, "texel slice",
                "only " + std::to_string(used) + " samples are bright enough to fit",
                "check the exposure and the validity mask of this texel");
  }
  const model::Vec3 measured_mean = WeightedMeanDirection(samples, [&](size_t k) { return samples[k].rho; });

  double shadowing_roughness = options_.initial_shadowing_roughness;
  const model::DualMicrofacetModel initial_model(eta_, ShadowingFor(shadowing_roughness));
  const Configurations configs = ComputeConfigurations(initial_model, samples, view);

  // (1) ln D for a fixed alpha. The last solve's unknowns and the sum of its data rows' squared
  // residuals are kept for the NDF's standard error.
  Eigen::VectorXd last_x;
  double last_data_ssr = 0.0;
  int last_data_rows = 0;
  SparseRows last_data;                // the last solve's data rows ...
  std::vector<int> last_row_sample;    // ... and the sample of each
  const auto solve_ln_d = [&](double alpha, bool with_symmetry) {
    SparseRows data;
    std::vector<int> row_sample;
    for (size_t k = 0; k < samples.size(); ++k) {
      const Sample& s = samples[k];
      // Samples too dark to use still get a row, with weight zero: the pattern of the normal
      // equations then depends only on the view and the light directions, so that texels
      // sharing them share one symbolic factorisation.
      if (s.weight <= 0 || !RowDefined(configs.entry[k], configs.exit[k], alpha)) continue;
      const double w = s.used ? std::sqrt(s.weight) : 0.0;
      const int row = data.rows++;
      row_sample.push_back(static_cast<int>(k));
      double rhs = 0.0;
      if (s.used) {
        rhs = std::log(s.rho);
        if (alpha > 0) rhs -= alpha * std::log(configs.entry[k].factor);
        if (alpha < 1) rhs -= (1 - alpha) * std::log(configs.exit[k].factor);
      }
      data.rhs.push_back(w * rhs);
      if (alpha > 0) {
        AddInterpolatedTerm(grid_, system.column, options_.horizon_ln_d, configs.entry[k].h, w * alpha, row, &data);
      }
      if (alpha < 1) {
        AddInterpolatedTerm(grid_, system.column, options_.horizon_ln_d, configs.exit[k].h, w * (1 - alpha), row,
                            &data);
      }
    }
    Eigen::VectorXd rhs;
    SparseMatrix normal = NormalMatrix(data, system.num_unknowns, &rhs);
    normal += system.smoothness_normal;
    rhs += system.smoothness_rhs;
    // Added with weight zero in the final pass so that both passes share one pattern.
    normal += (with_symmetry ? 1.0 : model::Square(options_.final_symmetry_weight)) * system.symmetry_normal;
    // Iterative only between alternations: a texel's first system is too far from the previous
    // texel's final one, and the final pass (without the symmetry rows) too far from the
    // alternations' for a few iterations; factorised, it serves the standard errors' solves below.
    const bool iterative = options_.iterative_solves && with_symmetry && last_x.size() > 0;
    const Eigen::VectorXd x = SolveNormalEquations(normal, rhs, last_x, iterative, state);
    std::vector<double> row_residual(data.rhs.size());
    for (size_t r = 0; r < data.rhs.size(); ++r) row_residual[r] = -data.rhs[r];
    for (const Triplet& t : data.triplets) row_residual[t.row()] += t.value() * x[t.col()];
    last_data_ssr = 0.0;
    for (double r : row_residual) last_data_ssr += r * r;
    last_data_rows = used;
    last_x = x;
    last_data = std::move(data);
    last_row_sample = std::move(row_sample);
    std::vector<double> ln_d(grid_.num_cells(), options_.horizon_ln_d);
    for (int c = 0; c < grid_.num_cells(); ++c) {
      if (system.column[c] >= 0) ln_d[c] = x[system.column[c]];
    }
    return ln_d;
  };

  // (2) alpha for a fixed D, by the paper's mean-direction criterion.
  const auto search_alpha = [&](const std::vector<double>& ln_d) {
    const model::TabulatedNdf ndf(grid_, ln_d);
    std::vector<double> rho_t, rho_b;
    EvaluateConfigurations(ndf, configs, &rho_t, &rho_b);
    return MinimumIncludingEnds(
        [&](double alpha) {
          const model::Vec3 mean = WeightedMeanDirection(samples, [&](size_t k) { return model::LogBlend(rho_t[k], rho_b[k], alpha); });
          return (mean - measured_mean).squaredNorm();
        },
        0.0, 1.0, 1e-4);
  };

  TexelFitResult result;
  double alpha = std::clamp(options_.initial_alpha, 0.0, 1.0);
  std::vector<double> ln_d = solve_ln_d(alpha, /*with_symmetry=*/true);
  // The alternations look for the fixed point alpha = g(alpha), g the alpha search on the ln D
  // solved for alpha. The paper's plain steps converge linearly (g's slope 0.3-0.7 for the
  // presets' lobes), so stopping when a step is below the tolerance leaves alpha short of the
  // fixed point, on the side of its start, by up to 3 times the tolerance; `secant_alternations`
  // steps towards it instead (docs/fitting.md, step 3). The last alternation ends at its step:
  // the final pass below solves ln D for that alpha afresh, so a with-symmetry solve there would
  // be discarded.
  AlphaFixedPoint fixed_point(options_.secant_alternations);
  for (result.alternations = 1;; ++result.alternations) {
    const double next_alpha = fixed_point.Next(alpha, search_alpha(ln_d));
    const double moved = std::abs(next_alpha - alpha);
    alpha = next_alpha;
    if (moved < options_.alpha_tolerance || result.alternations == options_.max_alternations) break;
    ln_d = solve_ln_d(alpha, /*with_symmetry=*/true);
  }
  ln_d = solve_ln_d(alpha, /*with_symmetry=*/false);

  // The NDF's width and its standard error: var = s^2 g^T N^-1 g, with N the final pass's normal
  // matrix, g the width's gradient in the unknowns and s^2 the data rows' mean squared residual
  // (docs/fitting.md, "Uncertainty"). The final pass factorised N and nothing has been factorised
  // since, so each solve with it is one back-substitution, exact to rounding (the conjugate
  // gradients preconditioned by the factor's single-precision copy took one iteration: a
  // back-substitution in single precision and a product with N, and stopped at 1e-9).
  const auto solve_final = [&](const Eigen::VectorXd& b) -> Eigen::VectorXd { return state->solver.solve(b); };
  if (options_.profile_uncertainty) {
    std::vector<double> d(grid_.num_cells());
    double mass = 0;
    for (int c = 0; c < grid_.num_cells(); ++c) {
      d[c] = std::exp(ln_d[c]);
      mass += d[c] * grid_.CellCenter(c).z() * grid_.CellSolidAngle(c);
    }
    const double width = NdfWidth(grid_, d);
    if (std::isfinite(width) && width > 0 && mass > 0 && last_x.size() == system.num_unknowns) {
      Eigen::VectorXd gradient = Eigen::VectorXd::Zero(system.num_unknowns);
      for (int c = 0; c < grid_.num_cells(); ++c) {
        if (system.column[c] < 0) continue;
        const double z = grid_.CellCenter(c).z();
        gradient[system.column[c]] =
            d[c] * z * grid_.CellSolidAngle(c) * (1.0 - z * z - width * width) / (2.0 * width * mass);
      }
      const Eigen::VectorXd solved = solve_final(gradient);
      const double s2 = last_data_ssr / std::max(1, last_data_rows - 1);
      result.ndf_width = width;
      result.ndf_width_se = StandardError(s2 * gradient.dot(solved));
    }
  }

  // alpha's profile (FinalPassProfile): with one view the data cannot tell how D is split between
  // h_T and h_B (above), so alpha trades against D, and D's normalisation against k_s; a system
  // with D held fixed cannot see that. The rows' derivative in alpha is
  // g_i = w_i (ln rho_T,i - ln rho_B,i), and D moves with alpha by -N^-1 u, which moves ln k_s
  // (D's mass) too.
  std::optional<FinalPassProfile> final_pass;
  if (options_.profile_uncertainty && last_x.size() == system.num_unknowns && last_data.rows > 0) {
    final_pass.emplace(last_data, system.num_unknowns, last_data_ssr, last_data_rows, solve_final);
  }
  if (final_pass) {
    const model::TabulatedNdf table(grid_, ln_d);
    Eigen::VectorXd g = Eigen::VectorXd::Zero(final_pass->rows());
    for (int r = 0; r < final_pass->rows(); ++r) {
      const int k = last_row_sample[r];
      const Sample& smp = samples[k];
      if (!smp.used || !(smp.weight > 0)) continue;
      const model::VirtualConfiguration& e = configs.entry[k];
      const model::VirtualConfiguration& x = configs.exit[k];
      if (!e.valid || !x.valid || !(e.factor > 0) || !(x.factor > 0)) continue;
      const double ln_t = std::log(e.factor) + std::log(std::max(table.D(e.h), 1e-300));
      const double ln_b = std::log(x.factor) + std::log(std::max(table.D(x.h), 1e-300));
      g[r] = std::sqrt(smp.weight) * (ln_t - ln_b);
    }
    const FinalPassProfile::Result profile = final_pass->Of(g);
    if (profile.variance >= 0) {
      result.alpha_profile_se = std::sqrt(profile.variance);
      double mass = 0, moved = 0;
      for (int c = 0; c < grid_.num_cells(); ++c) {
        if (system.column[c] < 0) continue;
        const double m = std::exp(ln_d[c]) * grid_.CellCenter(c).z() * grid_.CellSolidAngle(c);
        mass += m;
        moved -= m * profile.n_inv_u[system.column[c]];
      }
      if (mass > 0) result.k_s_profile_relative_se = std::abs(moved / mass) * result.alpha_profile_se;
    } else {
      result.alpha_profile_se = 0.5;  // the data do not pin alpha down
    }
  }

  // (3) Normalise D; its scale is the transmission scale k_s.
  model::TabulatedNdf ndf(grid_, ln_d);
  const double scale = ndf.Normalize();
  result.alpha = alpha;
  result.ln_d = ndf.ln_d();
  result.k_s = scale;

  // (4) Shadowing roughness and scale by Levenberg-Marquardt on the log residuals (eq. 15).
  std::vector<int> rows;
  for (size_t k = 0; k < samples.size(); ++k) {
    if (samples[k].used && RowDefined(configs.entry[k], configs.exit[k], alpha)) rows.push_back(static_cast<int>(k));
  }
  if (options_.refine_shadowing && shadowing_roughness > 0 && rows.size() >= 2) {
    double parameters[2] = {shadowing_roughness, std::log(scale)};
    auto* cost = new ceres::DynamicNumericDiffCostFunction<ShadowingResidual, ceres::CENTRAL>(
        new ShadowingResidual{&samples, &rows, &ndf, view, eta_, alpha});
    cost->AddParameterBlock(2);
    cost->SetNumResiduals(static_cast<int>(rows.size()));
    ceres::Problem problem;
    problem.AddResidualBlock(cost, nullptr, parameters);
    problem.SetParameterLowerBound(parameters, 0, 0.01);
    problem.SetParameterUpperBound(parameters, 0, 2.0);
    const ceres::Solver::Options solver_options = SmallProblemOptions(50);
    ceres::Solver::Summary summary;
    ceres::Solve(solver_options, &problem, &summary);
    if (summary.IsSolutionUsable()) {
      shadowing_roughness = parameters[0];
      result.k_s = std::exp(parameters[1]);
      // Its standard error: the sandwich covariance of the same residuals at the optimum.
      double cost_value = 0;
      std::vector<double> residuals;
      ceres::CRSMatrix jacobian;
      if (options_.profile_uncertainty &&
          problem.Evaluate(ceres::Problem::EvaluateOptions(), &cost_value, &residuals, nullptr, &jacobian)) {
        Eigen::MatrixXd j = Eigen::MatrixXd::Zero(jacobian.num_rows, jacobian.num_cols);
        for (int r = 0; r < jacobian.num_rows; ++r) {
          for (int k = jacobian.rows[r]; k < jacobian.rows[r + 1]; ++k) j(r, jacobian.cols[k]) = jacobian.values[k];
        }
        const Eigen::VectorXd r = Eigen::Map<const Eigen::VectorXd>(residuals.data(), static_cast<Eigen::Index>(residuals.size()));
        std::vector<model::Vec3> lights;
        for (int k : rows) lights.push_back(samples[k].light);
        const Neighbours neighbours = PointNeighbours(lights, options_.standard_errors.correlation_radius);
        result.shadowing_roughness_se = StandardError(SandwichCovariance(j, r, &neighbours)(0, 0));
      }
    }
  }
  result.shadowing_roughness = shadowing_roughness;
  // The sandwich above holds D fixed, but G and D trade much as alpha and D do (above): add the
  // roughness's profile over the final ln D pass, whose rows are the same log residuals.
  if (result.shadowing_roughness_se >= 0 && final_pass) {
    const FinalPassProfile::Result profile =
        final_pass->Of(ShadowingRowGradient(samples, view, eta_, alpha, shadowing_roughness, last_row_sample));
    // Where the data do not pin it down, half its bounds' range (as alpha's 0.5 above).
    result.shadowing_roughness_se =
        profile.variance >= 0 ? std::hypot(result.shadowing_roughness_se, std::sqrt(profile.variance)) : 1.0;
  }

  // Residuals and per-channel scales of the final model.
  MeasureResiduals(slice, samples, FittedTexel(grid_, eta_, result), &result);
  return result;
}

FittedTexel TexelFitter::Model(const TexelFitResult& fit) const {
  return FittedTexel(grid_, eta_, fit, options_.internal_reflection);
}

FittedTexel::FittedTexel(const model::Hemicube& grid, double eta, const TexelFitResult& fit, bool internal_reflection)
    : ndf_(std::make_shared<model::TabulatedNdf>(grid, fit.ln_d)), k_s_(fit.k_s) {
  params_.eta = eta;
  params_.alpha = fit.alpha;
  params_.shadowing = ShadowingFor(fit.shadowing_roughness);
  params_.internal_reflection = internal_reflection;
}

double FittedTexel::Rho(const model::Vec3& i, const model::Vec3& o) const {
  return k_s_ * model::SpecularRho(*ndf_, params_, i, o);
}

}  // namespace svbtdf::fit
