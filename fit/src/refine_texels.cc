#include "svbtdf/fit/refine_texels.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <optional>

#include "svbtdf/common/error.h"
#include "svbtdf/common/interrupt.h"
#include "svbtdf/common/minimize.h"
#include "svbtdf/common/parallel.h"
#include "svbtdf/common/progress.h"
#include "svbtdf/common/statistics.h"
#include "svbtdf/fit/ndf_error.h"
#include "svbtdf/common/least_squares.h"
#include "uncertainty.h"

namespace svbtdf::fit {
namespace {

// ---------------------------------------------------------------------------------------------
// Alpha and k_s with the texel's NDF fixed.

// The texel's samples against the model's shape m (its BTDF with k_s = 1): the best scale is
// k = sum(rho m) / sum(m^2), and the relative squared error at that scale is
// 1 - sum(rho m)^2 / (sum(m^2) sum(rho^2)).
struct ScaledFit {
  double scale = 0.0;
  double relative_squared_error = 1.0;
};

ScaledFit BestScale(const Eigen::ArrayXd& shape, const Eigen::ArrayXd& rho, double sum_rho_squared) {
  const double dot = rho.matrix().dot(shape.matrix()), shape_squared = shape.matrix().squaredNorm();
  ScaledFit fit;
  if (!(shape_squared > 0) || !(sum_rho_squared > 0)) return fit;
  fit.scale = std::max(0.0, dot / shape_squared);
  fit.relative_squared_error = std::max(0.0, 1.0 - dot * dot / (shape_squared * sum_rho_squared));
  return fit;
}

template <typename Values>
double SumOfSquares(const Values& v) {
  double sum = 0;
  for (double x : v) sum += x * x;
  return sum;
}

// A texel's samples seen through the dual-microfacet model: each sample's two virtual
// configurations, reduced to their factor and the hemicube weights of their half vectors. They
// depend on the view, the dots and the shadowing but not on D, so every NDF the refinement tries
// at a texel (the cluster's blend, each representative, the refitted blend) is looked up at the
// same places, computed once.
struct SampleLookups {
  struct Lookup {
    double factor = 0.0;  // 0 where the configuration does not exist
    model::Hemicube::Weights weights{};
    double LnD(const std::vector<double>& ln_d) const {
      double ln = 0;
      for (const auto& [cell, w] : weights) ln += w * ln_d[cell];
      return ln;
    }
  };
  std::vector<Lookup> entry, exit;
};

SampleLookups LookupsOf(const model::DualMicrofacetParams& params, const model::Hemicube& grid, const TexelSlice& slice) {
  const model::DualMicrofacetModel btdf(params.eta, params.shadowing);
  const auto lookup = [&](const model::VirtualConfiguration& c) {
    SampleLookups::Lookup l;
    if (!c.valid || !(c.factor > 0) || !(c.h.z() > 0)) return l;
    l.factor = c.factor;
    l.weights = grid.Interpolation(c.h);
    return l;
  };
  SampleLookups lookups;
  lookups.entry.reserve(slice.light.size());
  lookups.exit.reserve(slice.light.size());
  for (const model::Vec3& light : slice.light) {
    lookups.entry.push_back(lookup(btdf.RoughEntry(light, slice.view)));
    lookups.exit.push_back(lookup(btdf.RoughExit(light, slice.view)));
  }
  return lookups;
}

// Eigen's array exp and log are vectorised (as libm's are not) as long as the expression holds no
// select on a boolean array, so the masks below are 0/1 arrays that multiply, and a logarithm's
// argument is made positive before it is taken: the refinement's exponentials and logarithms
// were a third of its time.
//
// Every array they write is Eigen's own (aligned to the vector width), never a Map over a
// std::vector: Eigen computes the elements before the first aligned address with libm's scalar
// functions and the rest with its vectorised ones, which differ in the last bit, so a result
// written through a Map depended on where the heap put the vector (a fit resumed from its
// checkpoint then differed from the uninterrupted one; tests/cli/durability_test.cc).
Eigen::ArrayXd MaskOf(const Eigen::Array<bool, Eigen::Dynamic, 1>& condition) { return condition.cast<double>(); }

class ScalarRefiner {
 public:
  // The two virtual configurations do not depend on alpha (the model blends them in log space),
  // so each sample costs two NDF lookups however long the search for alpha runs. `lookups`: the
  // texel's (LookupsOf), for the dual-microfacet model.
  ScalarRefiner(const TexelBtdf& texel, const TexelSlice& slice, const SampleLookups* lookups)
      : slice_(slice),
        rho_(Eigen::Map<const Eigen::ArrayXd>(slice.rho.data(), static_cast<Eigen::Index>(slice.rho.size()))),
        sum_rho_squared_(SumOfSquares(slice.rho)) {
    const Eigen::Index n = static_cast<Eigen::Index>(slice_.light.size());
    if (texel.model() != MaterialModel::kDualMicrofacet) {  // a parametric lobe: its shape is fixed
      const TexelBtdf shape = texel.UnitShape();
      fixed_shape_.resize(n);
      for (Eigen::Index k = 0; k < n; ++k) fixed_shape_[k] = shape.Evaluate(slice_.light[k], slice_.view)[0];
      return;
    }
    const std::vector<double>& ln_d = texel.ndf().ln_d();
    // rho = factor D(h), its logarithm taken before the exponential (0 where rho vanishes).
    const auto logarithms = [&](const std::vector<SampleLookups::Lookup>& side, Eigen::ArrayXd* ln, Eigen::ArrayXd* rho) {
      Eigen::ArrayXd factor(n), ln_d_at(n);
      for (Eigen::Index k = 0; k < n; ++k) {
        const bool exists = side[k].factor > 0;
        factor[k] = exists ? side[k].factor : 1.0;
        ln_d_at[k] = exists ? side[k].LnD(ln_d) : 0.0;
      }
      *ln = factor.log() + ln_d_at;
      *rho = ln->exp();
      // Where the configuration does not exist (or its value underflows) rho and ln are 0.
      for (Eigen::Index k = 0; k < n; ++k) {
        if (!(side[k].factor > 0) || !((*rho)[k] > 0)) (*rho)[k] = (*ln)[k] = 0.0;
      }
    };
    logarithms(lookups->entry, &ln_t_, &rho_t_);
    logarithms(lookups->exit, &ln_b_, &rho_b_);
    both_ = MaskOf(rho_t_ > 0.0 && rho_b_ > 0.0);
  }

  // The shape of the model (its BTDF with k_s = 1) at blend weight `alpha` at every sample:
  // LogBlend with the logarithms taken once.
  const Eigen::ArrayXd& Shape(double alpha) {
    if (rho_t_.size() == 0) {
      shape_ = fixed_shape_;
    } else if (alpha >= 1.0 || alpha <= 0.0) {
      shape_ = alpha >= 1.0 ? rho_t_ : rho_b_;
    } else {
      shape_ = (alpha * ln_t_ + (1.0 - alpha) * ln_b_).exp() * both_;
    }
    return shape_;
  }

  ScaledFit FitAt(double alpha) { return BestScale(Shape(alpha), rho_, sum_rho_squared_); }

  // Relative RMSE of the model at `alpha` with the luminance scale `scale`.
  double RelativeRmse(double alpha, double scale) {
    const Eigen::ArrayXd& shape = Shape(alpha);
    double squared_error = 0;
    for (Eigen::Index k = 0; k < shape.size(); ++k) squared_error += model::Square(scale * shape[k] - rho_[k]);
    return std::sqrt(squared_error / sum_rho_squared_);
  }

  // d shape_k / d alpha at `alpha` for the shape last evaluated there (0 where the blend is flat).
  double ShapeAlphaDerivative(Eigen::Index k) const {
    if (rho_t_.size() == 0 || !(both_[k] > 0)) return 0.0;
    return shape_[k] * (ln_t_[k] - ln_b_[k]);
  }
  bool has_alpha() const { return rho_t_.size() > 0; }
  const Eigen::ArrayXd& last_shape() const { return shape_; }

  // Per-channel scales for the shape last evaluated.
  std::array<double, 3> ChannelScales(double luminance_scale) const {
    std::array<double, 3> scales;
    scales.fill(luminance_scale);
    if (static_cast<Eigen::Index>(slice_.rho_rgb.size()) != shape_.size()) return scales;
    const double shape_squared = SumOfSquares(shape_);
    if (!(shape_squared > 0)) return scales;
    for (int c = 0; c < 3; ++c) {
      double dot = 0;
      for (Eigen::Index k = 0; k < shape_.size(); ++k) dot += slice_.rho_rgb[k][c] * shape_[k];
      scales[c] = std::max(0.0, dot / shape_squared);
    }
    return scales;
  }

 private:
  const TexelSlice& slice_;
  Eigen::ArrayXd rho_;              // the slice's samples
  double sum_rho_squared_ = 0.0;
  Eigen::ArrayXd rho_t_, rho_b_;    // dual-microfacet: the two configurations (k_s = 1) ...
  Eigen::ArrayXd ln_t_, ln_b_;      // ... their logarithms (0 where they vanish) ...
  Eigen::ArrayXd both_;             // ... and 1 where both exist, 0 where the blend is 0
  Eigen::ArrayXd fixed_shape_;      // walter-ggx: the shape, which has no alpha
  Eigen::ArrayXd shape_;
};

struct RefinedScalars {
  double alpha = 0.5;
  double scale = 0.0;  // the luminance scale
  std::array<double, 3> k_s = {0, 0, 0};
  double relative_rmse = 1.0;
};

// Alpha by golden-section search (never ending worse than `start_alpha`), then k_s per channel.
RefinedScalars RefineScalars(ScalarRefiner* refiner, double start_alpha, bool refine_alpha, double tolerance) {
  RefinedScalars result;
  result.alpha = start_alpha;
  if (refine_alpha) {
    const double searched = common::GoldenSectionSearch([&](double a) { return refiner->FitAt(a).relative_squared_error; },
                                                0.0, 1.0, tolerance);
    if (refiner->FitAt(searched).relative_squared_error < refiner->FitAt(result.alpha).relative_squared_error) {
      result.alpha = searched;
    }
  }
  const ScaledFit best = refiner->FitAt(result.alpha);  // leaves the shape at alpha for the channels
  result.scale = best.scale;
  result.k_s = refiner->ChannelScales(best.scale);
  result.relative_rmse = std::sqrt(best.relative_squared_error);
  return result;
}

// ---------------------------------------------------------------------------------------------
// The weights over the representatives, refitted to the texel's samples.

// Each representative's two configurations at the texel's samples: T(k, j) and B(k, j) with
// representative j's own (normalised) D, under the texel's shadowing; a sample per row.
struct RepresentativeTerms {
  Eigen::MatrixXd t, b;
};

RepresentativeTerms TermsOf(const Material& material, const std::vector<int>& reps, const SampleLookups& lookups) {
  const Eigen::Index n = static_cast<Eigen::Index>(lookups.entry.size()), m = static_cast<Eigen::Index>(reps.size());
  // factor_k D_j(h_k): the logarithms of D first, then every exponential at once (vectorised).
  const auto terms_of = [&](const std::vector<SampleLookups::Lookup>& side) {
    Eigen::MatrixXd ln_d(n, m);
    Eigen::VectorXd factor(n);
    for (Eigen::Index k = 0; k < n; ++k) {
      const SampleLookups::Lookup& l = side[k];
      factor[k] = l.factor > 0 ? l.factor : 0.0;
      for (Eigen::Index j = 0; j < m; ++j) ln_d(k, j) = l.factor > 0 ? l.LnD(material.representative_ln_d[reps[j]]) : 0.0;
    }
    return Eigen::MatrixXd(factor.asDiagonal() * ln_d.array().exp().matrix());
  };
  RepresentativeTerms terms;
  terms.t = terms_of(lookups.entry);
  terms.b = terms_of(lookups.exit);
  return terms;
}

// The weights' least-squares problem: residuals (S_T^alpha S_B^(1-alpha) - rho) / |rho| with
// S = sum_j a_j T_j (resp. B_j), over x = (a_1 .. a_m, alpha), the unnormalised blend amounts and
// alpha (MinimizeInBox's interface). Evaluated over all samples at once: two matrix-vector
// products, then the logarithms and exponentials as arrays.
class BlendProblem {
 public:
  BlendProblem(const RepresentativeTerms& terms, const std::vector<double>& rho)
      : terms_(terms),
        rho_(Eigen::Map<const Eigen::ArrayXd>(rho.data(), static_cast<Eigen::Index>(rho.size()))),
        inverse_norm_(1.0 / std::sqrt(std::max(rho_.square().sum(), 1e-300))) {}

  // The residuals at x, and with `jacobian` their derivatives (a sample per row, a parameter per
  // column). Where a configuration is empty the blend is flat zero: no gradient to follow. Written
  // without selects so that the logarithms and exponentials are vectorised (MaskOf).
  void Evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* residuals, Eigen::MatrixXd* jacobian) const {
    const Eigen::Index m = terms_.t.cols();
    const double alpha = x[m];
    st_ = (terms_.t * x.head(m)).array();
    sb_ = (terms_.b * x.head(m)).array();
    smooth_ = MaskOf(st_ > 0.0 && sb_ > 0.0);
    // LogBlend, with the logarithms kept for the derivative in alpha (of 1 where not smooth, so
    // that they stay finite; those samples take the branches below).
    positive_st_ = smooth_ * st_ + (1.0 - smooth_);
    positive_sb_ = smooth_ * sb_ + (1.0 - smooth_);
    ln_st_ = positive_st_.log();
    ln_sb_ = positive_sb_.log();
    if (alpha >= 1.0 || alpha <= 0.0) {
      shape_ = (alpha >= 1.0 ? st_ : sb_).max(0.0);
    } else {
      shape_ = (alpha * ln_st_ + (1.0 - alpha) * ln_sb_).exp() * smooth_;
    }
    *residuals = ((shape_ - rho_) * inverse_norm_).matrix();
    if (!jacobian) return;
    const Eigen::ArrayXd scaled = shape_ * smooth_ * inverse_norm_;
    const Eigen::ArrayXd along_t = scaled * alpha / positive_st_, along_b = scaled * (1.0 - alpha) / positive_sb_;
    jacobian->resize(st_.size(), m + 1);
    for (Eigen::Index j = 0; j < m; ++j) {
      jacobian->col(j) = (along_t * terms_.t.col(j).array() + along_b * terms_.b.col(j).array()).matrix();
    }
    jacobian->col(m) = (scaled * (ln_st_ - ln_sb_)).matrix();
  }

  double Cost(const Eigen::VectorXd& x) const {
    Evaluate(x, &residuals_, nullptr);
    return 0.5 * residuals_.squaredNorm();
  }

  double Linearize(const Eigen::VectorXd& x, Eigen::MatrixXd* jtj, Eigen::VectorXd* jtr) const {
    Evaluate(x, &residuals_, &jacobian_);
    // Column by column: a few long dot products, cheaper than a general product's packing here.
    const Eigen::Index p = jacobian_.cols();
    jtj->resize(p, p);
    for (Eigen::Index a = 0; a < p; ++a) {
      for (Eigen::Index b = 0; b <= a; ++b) (*jtj)(a, b) = (*jtj)(b, a) = jacobian_.col(a).dot(jacobian_.col(b));
    }
    *jtr = jacobian_.transpose() * residuals_;
    return 0.5 * residuals_.squaredNorm();
  }

 private:
  const RepresentativeTerms& terms_;
  Eigen::ArrayXd rho_;
  double inverse_norm_;
  // Scratch, kept from one evaluation to the next.
  mutable Eigen::VectorXd residuals_;
  mutable Eigen::MatrixXd jacobian_;
  mutable Eigen::ArrayXd st_, sb_, smooth_, positive_st_, positive_sb_, ln_st_, ln_sb_, shape_;
};

// The texel's representatives and weights as stored (terms with weight 0 are unused slots).
struct TexelWeights {
  std::vector<int> reps;
  std::vector<double> weights;
};

TexelWeights ReadWeights(const Material& material, int x, int y) {
  TexelWeights w;
  for (int c = 0; c < material.weight_index.channels; ++c) {
    if (material.weight_value.at(x, y, c) == 0.0f) continue;
    w.reps.push_back(static_cast<int>(material.weight_index.at(x, y, c)));
    w.weights.push_back(material.weight_value.at(x, y, c));
  }
  return w;
}

void WriteWeights(const TexelWeights& w, int x, int y, Material* material) {
  for (int c = 0; c < material->weight_index.channels; ++c) {
    const bool used = c < static_cast<int>(w.reps.size());
    material->weight_index.at(x, y, c) = used ? static_cast<float>(w.reps[c]) : 0.0f;
    material->weight_value.at(x, y, c) = used ? static_cast<float>(w.weights[c]) : 0.0f;
  }
}

// How far below zero a blend amount may go, as a fraction of the texel's total: a texel outside
// the representatives' hull (sharper than the sharpest, say) needs a negative one.
constexpr double kExtrapolation = 3.0;

// Fits blend amounts a_j (each >= -kExtrapolation times their starting total) of the texel's
// representatives, and alpha, to its samples, starting from the clustering's weights; returns the
// weights w_j (sum 1) that make TexelNdf blend a_j D_j, or nothing when the fit does not run.
std::optional<TexelWeights> RefitWeights(const Material& material, const MaterialEvaluator& evaluator,
                                         const SampleLookups& lookups, const TexelBtdf& blended, const TexelWeights& start,
                                         const TexelSlice& slice, RepresentativeTerms* terms_out) {
  const size_t m = start.reps.size();
  if (m < 2) return std::nullopt;
  std::vector<double> scale(m);
  for (size_t j = 0; j < m; ++j) {
    scale[j] = evaluator.RepresentativeScale(start.reps[j]);
    if (!(scale[j] > 0)) return std::nullopt;
  }
  RepresentativeTerms& terms = *terms_out;
  terms = TermsOf(material, start.reps, lookups);
  // TexelNdf blends w_j s_j D_j; start there (negative weights clipped), at the texel's k_s.
  std::vector<double> amount(m);
  for (size_t j = 0; j < m; ++j) amount[j] = std::max(0.0, start.weights[j]) * scale[j];
  double total = std::accumulate(amount.begin(), amount.end(), 0.0);
  if (!(total > 0)) return std::nullopt;
  const double total_amount = model::Luminance(blended.params().k_s);
  for (double& a : amount) a *= total_amount / total;
  const Eigen::Index p = static_cast<Eigen::Index>(m) + 1;
  Eigen::VectorXd x(p), lower(p), upper(p);
  x << Eigen::Map<const Eigen::VectorXd>(amount.data(), p - 1), blended.params().alpha;
  lower.setConstant(-kExtrapolation * total_amount);
  upper.setConstant(std::numeric_limits<double>::infinity());
  lower[p - 1] = 0.0;
  upper[p - 1] = 1.0;
  const BlendProblem problem(terms, slice.rho);
  common::BoxLevenbergMarquardtOptions options;
  options.max_iterations = 25;
  if (!common::MinimizeInBox(problem, lower, upper, &x, options).usable) return std::nullopt;
  for (size_t j = 0; j < m; ++j) amount[j] = x[static_cast<Eigen::Index>(j)];

  TexelWeights refitted = start;
  total = 0;
  for (size_t j = 0; j < m; ++j) total += amount[j] / scale[j];
  if (!(total > 0)) return std::nullopt;
  double total_scaled = 0;
  for (size_t j = 0; j < m; ++j) total_scaled += amount[j];
  if (!(total_scaled > 0)) return std::nullopt;
  for (size_t j = 0; j < m; ++j) refitted.weights[j] = amount[j] / scale[j] / total;
  return refitted;
}

// The model error's variances of alpha, ln k_s (R, G, B) and the NDF width; -1 where not known.
using ModelVariance = std::array<double, 5>;

struct RefineContext {
  const SliceStore& store;
  const std::vector<bool>& use_dot;
  const RefineOptions& options;
  bool refine_alpha = false;
  // Neighbouring dots (uncertainty.h, PointNeighbours over the store's dots).
  std::vector<std::vector<std::pair<int, double>>> dot_neighbours;
  // Per texel: the model error's draw from its two fits (ModelErrorDraw), pooled over
  // neighbouring texels afterwards (AddModelError); null when the model error is left out. Each
  // texel writes only its own.
  std::vector<ModelVariance>* model_variance = nullptr;
};

// ---------------------------------------------------------------------------------------------
// Standard errors (docs/fitting.md, "Uncertainty").

// A representative's NDF table by the moments NdfWidth takes: its mass P = sum D z Omega, its
// moment M = sum D z s^2 Omega, its width and the width's standard error (from its own fit).
struct RepresentativeMoments {
  double mass = 0, moment = 0, width = 0, width_se = -1;
};

std::vector<RepresentativeMoments> MomentsOf(const Material& material, const model::Hemicube& grid) {
  std::vector<RepresentativeMoments> moments(material.representative_ln_d.size());
  for (size_t j = 0; j < moments.size(); ++j) {
    for (int c = 0; c < grid.num_cells(); ++c) {
      const double z = grid.CellCenter(c).z();
      const double m = std::exp(material.representative_ln_d[j][c]) * z * grid.CellSolidAngle(c);
      moments[j].mass += m;
      moments[j].moment += m * (1.0 - z * z);
    }
    moments[j].width = moments[j].mass > 0 ? std::sqrt(moments[j].moment / moments[j].mass) : 0.0;
    if (material.has_uncertainty()) moments[j].width_se = material.ndf_width_se.pixels[material.representative_texels[j]];
  }
  return moments;
}

// What the tables of the texel's representatives add to its width's variance: each table's own
// standard error, weighted by its share f_j of the texel's mass (W^2 = sum_j f_j W_j^2, so
// dW / dW_j = f_j W_j / W). -1 when a representative's is not known.
double TablesVariance(const std::vector<int>& reps, const std::vector<double>& amounts,
                      const std::vector<RepresentativeMoments>& moments, double width) {
  double total = 0;
  for (size_t j = 0; j < reps.size(); ++j) total += amounts[j] * moments[reps[j]].mass;
  if (!(total > 0) || !(width > 0)) return -1.0;
  double variance = 0;
  for (size_t j = 0; j < reps.size(); ++j) {
    const RepresentativeMoments& r = moments[reps[j]];
    if (!(r.width_se >= 0)) return -1.0;
    variance += model::Square(amounts[j] * r.mass / total * r.width / width * r.width_se);
  }
  return variance;
}

struct TexelUncertainty {
  double alpha_se = -1, scale_se = -1, prediction_se = -1;
  std::array<double, 3> rho_d_se = {-1, -1, -1};
  double ndf_width = -1, ndf_width_se = -1;
};

// rho_d's standard error from the samples where the fitted lobe is negligible (below 5% of
// rho_d, or 0.1% of the lobe's peak): there every sample is rho_d plus noise, and the store's
// floor estimate is their mean (docs/slice-store.md), whose standard error is their standard
// deviation over sqrt(n). Not known with fewer than 5 such samples.
std::array<double, 3> RhoDStandardError(const TexelSlice& slice, const Eigen::ArrayXd& shape,
                                        const std::array<double, 3>& k_s, const model::Rgb& rho_d, bool model_error) {
  std::array<double, 3> se = {-1, -1, -1};
  if (static_cast<Eigen::Index>(slice.measured_rgb.size()) != shape.size() || shape.size() == 0) return se;
  const double scale = (k_s[0] + k_s[1] + k_s[2]) / 3.0;
  const double peak = scale * *std::max_element(shape.begin(), shape.end());
  const double threshold = std::max(0.05 * model::Luminance(rho_d), 1e-3 * peak);
  for (int c = 0; c < 3; ++c) {
    double sum = 0, sum_squared = 0;
    int n = 0;
    for (Eigen::Index k = 0; k < shape.size(); ++k) {
      if (scale * shape[k] > threshold) continue;
      const double e = slice.measured_rgb[k][c] - k_s[c] * shape[k] - rho_d[c];
      sum += e;
      sum_squared += e * e;
      ++n;
    }
    if (n < 5) continue;
    const double mean = sum / n;
    const double variance = std::max(0.0, (sum_squared - n * mean * mean) / (n - 1)) / n;
    // The floor samples' mean offset from the fitted model: a second estimate of the floor (the
    // fit's samples, unweighted, chosen by the fitted lobe) against the store's (its own clipped,
    // weighted set); their disagreement counts as the store's error. (Moving rho_d by it made
    // rho_d worse on `small`: the store's is the better of the two; docs/validation.md.)
    se[c] = std::sqrt(variance + (model_error ? mean * mean : 0.0));
  }
  return se;
}

// alpha and the scale with the texel's NDF fixed: the two columns shape_k and scale d shape_k /
// d alpha of the residuals scale shape_k - rho_k (only the scale for a model without alpha).
void ScalarUncertainty(ScalarRefiner* refiner, const TexelSlice& slice, const RefinedScalars& best, bool with_alpha,
                       const Neighbours* neighbours, TexelUncertainty* u) {
  const Eigen::ArrayXd& shape = refiner->Shape(best.alpha);
  const Eigen::Index n = shape.size();
  const int p = with_alpha && refiner->has_alpha() ? 2 : 1;
  Eigen::MatrixXd j(n, p);
  Eigen::VectorXd r(n);
  double norm = 0;
  for (Eigen::Index k = 0; k < n; ++k) {
    j(k, 0) = shape[k];
    if (p == 2) j(k, 1) = best.scale * refiner->ShapeAlphaDerivative(k);
    r[k] = best.scale * shape[k] - slice.rho[k];
    norm += slice.rho[k] * slice.rho[k];
  }
  const Eigen::MatrixXd c = SandwichCovariance(j, r, neighbours);
  u->scale_se = StandardError(c(0, 0));
  if (p == 2) u->alpha_se = StandardError(c(1, 1));
  if (norm > 0) u->prediction_se = StandardError((j * c).cwiseProduct(j).sum() / norm);
}

// alpha and the blend amounts a_j of the representatives' NDFs (whose sum is the scale), at the
// refined texel, from the weights' own system (BlendProblem): the NDF's freedom the weights give is
// then counted in alpha's and the scale's errors, and the width's error is the weights'.
void BlendUncertainty(const RepresentativeTerms& terms, const TexelSlice& slice, const TexelWeights& weights,
                      const std::vector<double>& rep_scale, const RefinedScalars& best,
                      const std::vector<RepresentativeMoments>& moments, double width, const Neighbours* neighbours,
                      TexelUncertainty* u) {
  const size_t m = weights.reps.size();
  std::vector<double> amount(m);
  double total = 0;
  for (size_t j = 0; j < m; ++j) total += weights.weights[j] * rep_scale[j];
  if (!(total != 0)) return;
  for (size_t j = 0; j < m; ++j) amount[j] = best.scale * weights.weights[j] * rep_scale[j] / total;
  Eigen::VectorXd x(static_cast<Eigen::Index>(m) + 1);
  for (size_t i = 0; i < m; ++i) x[static_cast<Eigen::Index>(i)] = amount[i];
  x[static_cast<Eigen::Index>(m)] = best.alpha;
  Eigen::VectorXd r;
  Eigen::MatrixXd j;
  BlendProblem(terms, slice.rho).Evaluate(x, &r, &j);
  const Eigen::MatrixXd c = SandwichCovariance(j, r, neighbours);
  u->alpha_se = StandardError(c(m, m));
  u->scale_se = StandardError(c.topLeftCorner(m, m).sum());
  u->prediction_se = StandardError((j * c).cwiseProduct(j).sum());  // the residuals are relative already
  // The width W = sqrt(sum a_j M_j / sum a_j P_j): dW / da_j = (M_j - W^2 P_j) / (2 W sum a P).
  double mass = 0;
  for (size_t i = 0; i < m; ++i) mass += amount[i] * moments[weights.reps[i]].mass;
  if (!(width > 0) || !(mass > 0)) return;
  Eigen::VectorXd g(m);
  for (size_t i = 0; i < m; ++i) {
    const RepresentativeMoments& rm = moments[weights.reps[i]];
    g[i] = (rm.moment - width * width * rm.mass) / (2.0 * width * mass);
  }
  const double tables = TablesVariance(weights.reps, amount, moments, width);
  const double from_weights = g.dot(c.topLeftCorner(m, m) * g);
  u->ndf_width_se = tables >= 0 ? StandardError(from_weights + tables) : -1.0;
}

// One draw of the model error (AddModelError): the squared distance of the other fit of the
// texel's samples from the chosen one in alpha, ln k_s (R, G, B) and the NDF width; -1 where a
// fit leaves it unknown.
ModelVariance ModelErrorDraw(const RefinedScalars& other, const RefinedScalars& best, double width_blended,
                             double width_refitted) {
  ModelVariance v;
  v[0] = model::Square(other.alpha - best.alpha);
  for (int c = 0; c < 3; ++c) {
    v[1 + c] = other.k_s[c] > 0 && best.k_s[c] > 0 ? model::Square(std::log(other.k_s[c] / best.k_s[c])) : -1.0;
  }
  v[4] = width_blended > 0 && width_refitted > 0 ? model::Square(width_refitted - width_blended) : -1.0;
  return v;
}

// The neighbours of a slice's samples (SampleNeighbours), kept for the next texel: the texels of
// a tile mostly see the same dots, and building the lists took 4% of the refinement.
class NeighbourCache {
 public:
  const Neighbours& For(const std::vector<std::vector<std::pair<int, double>>>& dot_neighbours,
                        const std::vector<int>& dots) {
    if (!valid_ || dots != dots_) {
      std::vector<int> sample_of_dot;
      neighbours_ = SampleNeighbours(dot_neighbours, dots, &sample_of_dot);
      dots_ = dots;
      valid_ = true;
    }
    return neighbours_;
  }

 private:
  bool valid_ = false;
  std::vector<int> dots_;
  Neighbours neighbours_;
};

// Refines one texel in place; returns its relative RMSE on its own samples before and after, or
// nothing when it has no usable samples (it then keeps the blend).
std::optional<std::pair<double, double>> RefineTexel(const RefineContext& context, const MaterialEvaluator& evaluator,
                                                     const model::Hemicube& grid, bool refit_weights, int64_t t,
                                                     const TexelSlice& slice, const std::vector<RepresentativeMoments>& moments,
                                                     bool representatives_pass, NeighbourCache* neighbour_cache,
                                                     Material* material) {
  const int x = static_cast<int>(t % material->width), y = static_cast<int>(t / material->width);
  if (!(SumOfSquares(slice.rho) > 0)) return std::nullopt;
  const TexelWeights blended_weights = ReadWeights(*material, x, y);
  const TexelBtdf blended = evaluator.Texel(x, y);
  const double start_alpha = blended.params().alpha;
  const bool dual_model = material->model == MaterialModel::kDualMicrofacet;
  const SampleLookups lookups = dual_model ? LookupsOf(blended.params(), grid, slice) : SampleLookups();
  ScalarRefiner refiner(blended, slice, &lookups);
  const double before = refiner.RelativeRmse(start_alpha, model::Luminance(blended.params().k_s));
  const double tolerance = context.options.alpha_tolerance;
  RefinedScalars best = RefineScalars(&refiner, start_alpha, context.refine_alpha, tolerance);
  std::optional<ScalarRefiner> refitted_refiner;
  RepresentativeTerms terms;
  std::optional<TexelWeights> kept_weights;  // the refitted weights, when kept
  // The two fits of the same samples with two NDFs (the cluster's blend and the refitted one), for
  // the model error: how far alpha, k_s and the width move with D's choice (docs/fitting.md).
  const bool uncertainty = context.options.uncertainty && material->has_uncertainty();
  std::optional<RefinedScalars> other;
  double width_blended = -1, width_refitted = -1;
  if (refit_weights) {
    if (uncertainty && dual_model) width_blended = NdfWidth(grid, evaluator.TexelCellD(x, y));
    if (const auto refitted = RefitWeights(*material, evaluator, lookups, blended, blended_weights, slice, &terms)) {
      WriteWeights(*refitted, x, y, material);
      if (uncertainty && dual_model) width_refitted = NdfWidth(grid, evaluator.TexelCellD(x, y));
      refitted_refiner.emplace(evaluator.Texel(x, y), slice, &lookups);
      const RefinedScalars with_refitted =
          RefineScalars(&*refitted_refiner, start_alpha, context.refine_alpha, tolerance);
      if (with_refitted.relative_rmse < best.relative_rmse) {
        other = best;
        best = with_refitted;
        kept_weights = refitted;
      } else {
        other = with_refitted;
        WriteWeights(blended_weights, x, y, material);
      }
    }
  }
  if (context.options.uncertainty && material->has_uncertainty()) {
    TexelUncertainty u;
    ScalarRefiner& chosen = kept_weights ? *refitted_refiner : refiner;
    const bool dual = material->model == MaterialModel::kDualMicrofacet;
    // The texel's NDF width (a representative keeps its own fit's, with its error).
    const TexelWeights& weights = kept_weights ? *kept_weights : blended_weights;
    if (dual && !representatives_pass) {
      // The refit measured the width of the weights kept already: the tables need no third blend.
      const double measured = kept_weights ? width_refitted : width_blended;
      u.ndf_width = measured >= 0 ? measured : NdfWidth(grid, evaluator.TexelCellD(x, y));
      std::vector<double> amounts(weights.reps.size());
      for (size_t j = 0; j < amounts.size(); ++j) amounts[j] = weights.weights[j] * evaluator.RepresentativeScale(weights.reps[j]);
      const double tables = TablesVariance(weights.reps, amounts, moments, u.ndf_width);
      u.ndf_width_se = tables >= 0 ? std::sqrt(tables) : -1.0;
    }
    const Neighbours* correlated = nullptr;
    if (slice.dot.size() == slice.rho.size() && !slice.dot.empty()) {
      correlated = &neighbour_cache->For(context.dot_neighbours, slice.dot);
    }
    if (kept_weights) {
      std::vector<double> rep_scale(weights.reps.size());
      for (size_t j = 0; j < rep_scale.size(); ++j) rep_scale[j] = evaluator.RepresentativeScale(weights.reps[j]);
      BlendUncertainty(terms, slice, weights, rep_scale, best, moments, u.ndf_width, correlated, &u);
    } else {
      ScalarUncertainty(&chosen, slice, best, context.refine_alpha, correlated, &u);
    }
    chosen.Shape(best.alpha);
    u.rho_d_se = RhoDStandardError(slice, chosen.last_shape(), best.k_s, blended.params().rho_d,
                                   context.options.standard_errors.model_error);
    // The assembly left the representatives' profile errors (what the data cannot tell apart)
    // in the maps; the texel's own statistical errors add to them.
    const double profile_alpha = material->alpha_se.at(x, y);
    const double profile_k_s = material->k_s.at(x, y) > 0 && material->k_s_se.at(x, y) >= 0
                                   ? material->k_s_se.at(x, y) / material->k_s.at(x, y)
                                   : 0.0;
    // The model error is only recorded here: AddModelError adds it once every texel has its own
    // draw, to pool them. The maps below hold the texel's statistical errors until then.
    if (other && context.model_variance) {
      (*context.model_variance)[t] = ModelErrorDraw(*other, best, width_blended, width_refitted);
    }
    material->alpha_se.at(x, y) = static_cast<float>(
        u.alpha_se >= 0 ? std::sqrt(model::Square(u.alpha_se) + model::Square(std::max(0.0, profile_alpha))) : -1.0);
    for (int c = 0; c < 3; ++c) {
      const double relative = u.scale_se >= 0 && best.scale > 0 ? u.scale_se / best.scale : -1.0;
      material->k_s_se.at(x, y, c) = static_cast<float>(
          relative >= 0 ? best.k_s[c] * std::sqrt(model::Square(relative) + model::Square(profile_k_s)) : -1.0);
      material->rho_d_se.at(x, y, c) = static_cast<float>(u.rho_d_se[c]);
    }
    material->prediction_se.at(x, y) = static_cast<float>(u.prediction_se);
    if (dual && !representatives_pass) {
      material->ndf_width.at(x, y) = static_cast<float>(u.ndf_width);
      material->ndf_width_se.at(x, y) = static_cast<float>(u.ndf_width_se);
    }
  }
  material->alpha.at(x, y) = static_cast<float>(best.alpha);
  for (int c = 0; c < 3; ++c) material->k_s.at(x, y, c) = static_cast<float>(best.k_s[c]);
  material->residual.at(x, y) = static_cast<float>(best.relative_rmse);
  return std::make_pair(before, best.relative_rmse);
}

// With the internal-reflection term (material version 4), the refinement fits the dual-microfacet
// terms to what the term leaves of the samples, the term taken with the texel's parameters before
// refining (one fixed-point step of the fit's, texel_fit.h step 5). The residual it records is
// then of that remainder.
TexelSlice WithoutInternalReflectionOf(const Material& material, const MaterialEvaluator& evaluator, int64_t t,
                                       const TexelSlice& slice) {
  const TexelBtdf texel = evaluator.Texel(static_cast<int>(t % material.width), static_cast<int>(t / material.width));
  const model::DualMicrofacetParams& p = texel.params();
  return WithoutInternalReflection(slice, texel.ndf(), p.eta, p.alpha, model::Luminance(p.k_s), p.k_s);
}

// Refines `texels` in parallel (each writes only its own pixels of the maps) and returns the
// before/after pairs of those refined.
std::vector<std::pair<double, double>> RefineAll(const RefineContext& context, const std::vector<int64_t>& texels,
                                                 bool refit_weights, bool representatives_pass, const char* label,
                                                 Material* material) {
  // Constructed here, after any earlier pass changed the representatives' k_s: the blend scales
  // it reads are then the ones a reader of the saved material computes.
  const MaterialEvaluator evaluator(*material);
  const model::Hemicube grid(material->ndf_resolution);
  const std::vector<RepresentativeMoments> moments =
      context.options.uncertainty && material->has_uncertainty() ? MomentsOf(*material, grid) : std::vector<RepresentativeMoments>();
  std::vector<std::optional<std::pair<double, double>>> results(texels.size());
  std::unique_ptr<common::ProgressBar> progress;
  if (context.options.progress) {
    progress = std::make_unique<common::ProgressBar>(label, static_cast<int64_t>(texels.size()), "texels");
  }
  // Tile by tile: one read per tile rather than one per dot and texel (slice_store.h).
  const int64_t tile_texels = context.store.info().tile_texels;
  std::vector<size_t> order(texels.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return texels[a] < texels[b]; });
  std::vector<float> tile_samples;
  for (size_t begin = 0; begin < order.size();) {
    const int64_t tile = texels[order[begin]] / tile_texels;
    size_t end = begin;
    while (end < order.size() && texels[order[end]] / tile_texels == tile) ++end;
    context.store.ReadTile(tile, &tile_samples);
    common::ParallelFor(static_cast<int64_t>(end - begin), context.options.threads, 16, [&](int64_t a, int64_t b) {
      NeighbourCache neighbour_cache;
      for (int64_t k = a; k < b; ++k) {
        common::ThrowIfInterrupted("refining");
        const size_t index = order[begin + k];
        TexelSlice slice = context.store.MakeTexelSlice(texels[index], tile_samples, context.use_dot);
        if (material->internal_reflection) slice = WithoutInternalReflectionOf(*material, evaluator, texels[index], slice);
        results[index] = RefineTexel(context, evaluator, grid, refit_weights, texels[index], slice, moments,
                                     representatives_pass, &neighbour_cache, material);
        if (progress) progress->Advance();
      }
    });
    begin = end;
  }
  if (progress) progress->Finish();
  std::vector<std::pair<double, double>> refined;
  for (const auto& r : results) {
    if (r) refined.push_back(*r);
  }
  return refined;
}

// The mean of the model error's draws over the texels within `radius` of (x, y) on the grid (0:
// the texel's own), per parameter over the draws that are known; 0 where none is.
ModelVariance PooledModelVariance(const std::vector<ModelVariance>& model_variance, const Material& material, int x,
                                  int y, int radius) {
  ModelVariance sum{}, count{};
  for (int ny = std::max(0, y - radius); ny <= std::min(material.height - 1, y + radius); ++ny) {
    for (int nx = std::max(0, x - radius); nx <= std::min(material.width - 1, x + radius); ++nx) {
      const ModelVariance& v = model_variance[static_cast<int64_t>(ny) * material.width + nx];
      for (int p = 0; p < 5; ++p) {
        if (v[p] >= 0) sum[p] += v[p], count[p] += 1;
      }
    }
  }
  for (int p = 0; p < 5; ++p) sum[p] = count[p] > 0 ? sum[p] / count[p] : 0.0;
  return sum;
}

// The model error (docs/fitting.md, "Uncertainty"): what the data cannot tell apart is decided by
// the NDF the texel is given, and each interpolated texel was fitted twice, with its cluster's
// blend of the representatives' tables and with its own refitted blend. How far alpha, ln k_s and
// the width moved between the two is one draw of that error; its square, averaged over the texels
// within `radius` on the grid (one draw alone makes an error bar with heavy tails; a
// representative, fitted once, takes its neighbours'), is added to each texel's variance.
void AddModelError(const std::vector<ModelVariance>& model_variance, int radius, Material* material) {
  const auto add_to = [](float* se, double variance) {
    if (*se < 0) return;
    *se = static_cast<float>(std::sqrt(model::Square(*se) + variance));
  };
  for (int y = 0; y < material->height; ++y) {
    for (int x = 0; x < material->width; ++x) {
      const ModelVariance mean = PooledModelVariance(model_variance, *material, x, y, radius);
      add_to(&material->alpha_se.at(x, y), mean[0]);
      for (int c = 0; c < 3; ++c) add_to(&material->k_s_se.at(x, y, c), mean[1 + c] * model::Square(material->k_s.at(x, y, c)));
      if (material->ndf_width.width > 0) add_to(&material->ndf_width_se.at(x, y), mean[4]);
    }
  }
}

}  // namespace

RefineStatistics RefineTexels(const SliceStore& store, const std::vector<bool>& use_dot,
                              const std::vector<int64_t>& texels, const RefineOptions& options, Material* material) {
  const int width = material->width;
  if (store.info().texels_x != width || store.info().texels_y != material->height) {
    common::ThrowInvalidInput(store.folder().string(), "does not match the material's texel grid");
  }
  std::vector<uint8_t> is_representative(static_cast<size_t>(width) * material->height, 0);
  for (int64_t t : material->representative_texels) is_representative[t] = 1;
  const bool dual = material->model == MaterialModel::kDualMicrofacet;
  std::vector<int64_t> representatives, interpolated;
  for (int64_t t : texels) {
    if (t < 0 || t >= static_cast<int64_t>(is_representative.size())) {
      common::ThrowInvalidInput("refinement", "texel " + std::to_string(t) + " is outside the material");
    }
    if (!is_representative[t]) {
      interpolated.push_back(t);
    } else if (dual && options.refine_alpha) {
      representatives.push_back(t);  // the baseline's representatives have nothing to refine
    }
  }
  std::vector<ModelVariance> model_variance;
  RefineContext context{store, use_dot, options, options.refine_alpha && dual, {}, nullptr};
  const bool model_error = options.uncertainty && material->has_uncertainty() && dual && options.standard_errors.model_error;
  if (model_error) {
    ModelVariance unknown;
    unknown.fill(-1.0);
    model_variance.assign(static_cast<size_t>(width) * material->height, unknown);
    context.model_variance = &model_variance;
  }
  if (options.uncertainty && material->has_uncertainty()) {
    context.dot_neighbours = PointNeighbours(store.geometry().dots, options.standard_errors.correlation_radius);
  }
  RefineStatistics statistics;
  // The representatives first (alpha and k_s only): the interpolated texels blend their D by the
  // representatives' k_s, so those must be final before the weights are refitted against them.
  statistics.representatives =
      static_cast<int64_t>(RefineAll(context, representatives, false, true, "refine representatives", material).size());
  const std::vector<std::pair<double, double>> refined =
      RefineAll(context, interpolated, options.refit_weights && dual, false, "refine", material);
  std::vector<double> before, after;
  for (const auto& [b, a] : refined) {
    before.push_back(b);
    after.push_back(a);
  }
  if (model_error) AddModelError(model_variance, options.standard_errors.model_error_pool_radius, material);
  statistics.texels = static_cast<int64_t>(refined.size());
  statistics.median_rmse_blended = common::Median(before);
  statistics.median_rmse_refined = common::Median(after);
  return statistics;
}

}  // namespace svbtdf::fit
