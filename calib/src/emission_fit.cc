#include "svbtdf/calib/emission_fit.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <string>

#include <Eigen/Dense>

#include "svbtdf/common/error.h"

namespace svbtdf::calib {
namespace {

// The two nodes a linear interpolation at theta uses, and their weights.
struct Hat {
  int k = 0;
  double f = 0.0;  // weight of node k + 1; node k has 1 - f
};

Hat HatAt(double theta_deg, double step_deg, int nodes) {
  const double x = theta_deg / step_deg;
  Hat h;
  h.k = std::min(static_cast<int>(x), nodes - 2);
  h.f = x - h.k;
  return h;
}

// Runs of observations of one group, as index ranges into `order`.
std::vector<std::pair<size_t, size_t>> GroupRuns(const std::vector<EmissionObservation>& obs,
                                                 const std::vector<size_t>& order) {
  std::vector<std::pair<size_t, size_t>> runs;
  for (size_t a = 0; a < order.size();) {
    size_t b = a + 1;
    while (b < order.size() && obs[order[b]].group == obs[order[a]].group) ++b;
    runs.push_back({a, b});
    a = b;
  }
  return runs;
}

// The single cos^n that best explains the observations, each group with its own scale; returns
// n and the weighted RMS of its ln residuals.
std::pair<double, double> FitCosPower(const std::vector<EmissionObservation>& obs, const std::vector<size_t>& order,
                                      const std::vector<std::pair<size_t, size_t>>& runs) {
  auto log_cos = [](double theta_deg) { return std::log(std::max(1e-6, std::cos(theta_deg * std::numbers::pi / 180.0))); };
  double sxy = 0, sxx = 0;
  std::vector<std::pair<double, double>> means(runs.size());  // (mean x, mean y) per group
  for (size_t g = 0; g < runs.size(); ++g) {
    double sw = 0, swx = 0, swy = 0;
    for (size_t j = runs[g].first; j < runs[g].second; ++j) {
      const EmissionObservation& o = obs[order[j]];
      sw += o.weight;
      swx += o.weight * log_cos(o.theta_deg);
      swy += o.weight * std::log(o.value);
    }
    means[g] = {swx / sw, swy / sw};
    for (size_t j = runs[g].first; j < runs[g].second; ++j) {
      const EmissionObservation& o = obs[order[j]];
      const double x = log_cos(o.theta_deg) - means[g].first, y = std::log(o.value) - means[g].second;
      sxy += o.weight * x * y;
      sxx += o.weight * x * x;
    }
  }
  const double n = sxx > 0 ? sxy / sxx : 0.0;
  double swr2 = 0, sw = 0;
  for (size_t g = 0; g < runs.size(); ++g) {
    for (size_t j = runs[g].first; j < runs[g].second; ++j) {
      const EmissionObservation& o = obs[order[j]];
      const double r = (std::log(o.value) - means[g].second) - n * (log_cos(o.theta_deg) - means[g].first);
      swr2 += o.weight * r * r;
      sw += o.weight;
    }
  }
  return {n, std::sqrt(swr2 / sw)};
}

}  // namespace

EmissionFit FitEmissionProfile(const std::vector<EmissionObservation>& all, const EmissionFitOptions& options) {
  std::vector<EmissionObservation> obs;
  obs.reserve(all.size());
  for (const EmissionObservation& o : all) {
    if (std::isfinite(o.value) && o.value > 0 && std::isfinite(o.weight) && o.weight > 0 && o.theta_deg >= 0 &&
        o.theta_deg < 89.0) {
      obs.push_back(o);
    }
  }
  if (obs.empty()) common::ThrowInvalidInput("emission profile", "has no positive measurement to fit");
  const double step = options.step_deg;
  double max_theta = 0;
  for (const EmissionObservation& o : obs) max_theta = std::max(max_theta, o.theta_deg);
  const int nodes = std::max(2, std::min(static_cast<int>(max_theta / step) + 2, static_cast<int>(89.0 / step) + 1));

  std::vector<size_t> order(obs.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return obs[a].group < obs[b].group; });
  const std::vector<std::pair<size_t, size_t>> runs = GroupRuns(obs, order);

  // Normal equations of ln R = a_t + sum_k B_k(theta) g_k with every a_t eliminated: per group,
  // sum w b b^T - (sum w b)(sum w b)^T / sum w, and the same for the right-hand side.
  Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(nodes, nodes);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(nodes);
  std::vector<double> group_sw(runs.size()), group_swy(runs.size());
  std::vector<Eigen::VectorXd> group_swb(runs.size());
  double total_weight = 0;
  for (size_t g = 0; g < runs.size(); ++g) {
    Eigen::VectorXd swb = Eigen::VectorXd::Zero(nodes);
    double sw = 0, swy = 0;
    for (size_t j = runs[g].first; j < runs[g].second; ++j) {
      const EmissionObservation& o = obs[order[j]];
      const Hat h = HatAt(o.theta_deg, step, nodes);
      const double y = std::log(o.value), w = o.weight;
      const double b0 = 1.0 - h.f, b1 = h.f;
      normal(h.k, h.k) += w * b0 * b0;
      normal(h.k, h.k + 1) += w * b0 * b1;
      normal(h.k + 1, h.k) += w * b0 * b1;
      normal(h.k + 1, h.k + 1) += w * b1 * b1;
      rhs(h.k) += w * b0 * y;
      rhs(h.k + 1) += w * b1 * y;
      swb(h.k) += w * b0;
      swb(h.k + 1) += w * b1;
      sw += w;
      swy += w * y;
    }
    normal.noalias() -= swb * swb.transpose() / sw;
    rhs -= swb * (swy / sw);
    group_sw[g] = sw;
    group_swy[g] = swy;
    group_swb[g] = std::move(swb);
    total_weight += sw;
  }
  // Smoothness: a second-difference penalty, scaled to the data so that it bends the table only
  // where the observations are few.
  const double lambda = options.smoothness * total_weight / nodes;
  for (int k = 1; k + 1 < nodes; ++k) {
    const int index[3] = {k - 1, k, k + 1};
    const double d[3] = {1.0, -2.0, 1.0};
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) normal(index[a], index[b]) += lambda * d[a] * d[b];
    }
  }
  // The scale is free: it is fixed at the node with the most data (so that the standard errors
  // below are those of the shape, not of an extrapolated P(0)), then moved to P(0) = 1.
  std::vector<double> node_weight(nodes, 0.0);
  for (size_t j = 0; j < obs.size(); ++j) {
    const Hat h = HatAt(obs[j].theta_deg, step, nodes);
    node_weight[h.k] += obs[j].weight * (1.0 - h.f);
    node_weight[h.k + 1] += obs[j].weight * h.f;
  }
  const int anchor = static_cast<int>(std::max_element(node_weight.begin(), node_weight.end()) - node_weight.begin());
  const int free = nodes - 1;
  std::vector<int> unknown;  // node of each unknown
  for (int k = 0; k < nodes; ++k) {
    if (k != anchor) unknown.push_back(k);
  }
  Eigen::MatrixXd reduced(free, free);
  Eigen::VectorXd reduced_rhs(free);
  for (int a = 0; a < free; ++a) {
    reduced_rhs(a) = rhs(unknown[a]);
    for (int b = 0; b < free; ++b) reduced(a, b) = normal(unknown[a], unknown[b]);
  }
  const Eigen::LDLT<Eigen::MatrixXd> solver(reduced);
  const Eigen::VectorXd solution = solver.solve(reduced_rhs);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(nodes);
  for (int a = 0; a < free; ++a) g(unknown[a]) = solution(a);

  // Residuals with each group's offset at its optimum.
  EmissionFit fit;
  EmissionFitReport& report = fit.report;
  double swr2 = 0;
  std::vector<int64_t> near(nodes, 0);
  for (size_t t = 0; t < runs.size(); ++t) {
    const double offset = (group_swy[t] - group_swb[t].dot(g)) / group_sw[t];
    for (size_t j = runs[t].first; j < runs[t].second; ++j) {
      const EmissionObservation& o = obs[order[j]];
      const Hat h = HatAt(o.theta_deg, step, nodes);
      const double r = std::log(o.value) - offset - ((1.0 - h.f) * g(h.k) + h.f * g(h.k + 1));
      swr2 += o.weight * r * r;
      for (int k = std::max(0, h.k - 1); k <= std::min(nodes - 1, h.k + 2); ++k) {
        if (std::abs(o.theta_deg - k * step) < step) ++near[k];
      }
    }
  }
  const double dof = std::max(1.0, static_cast<double>(obs.size()) - free - static_cast<double>(runs.size()));
  const double sigma2 = swr2 / dof;
  const Eigen::MatrixXd covariance = sigma2 * solver.solve(Eigen::MatrixXd::Identity(free, free));
  report.observations = static_cast<int64_t>(obs.size());
  report.texels = static_cast<int64_t>(runs.size());
  report.residual_rms = std::sqrt(swr2 / total_weight);
  report.table_std.assign(nodes, 0.0);
  for (int a = 0; a < free; ++a) report.table_std[unknown[a]] = std::sqrt(std::max(0.0, covariance(a, a)));
  report.table_observations = near;

  int first = -1, last = -1;
  for (int k = 0; k < nodes; ++k) {
    if (near[k] >= options.min_node_observations && report.table_std[k] <= options.max_node_std) {
      if (first < 0) first = k;
      last = k;
    }
  }
  if (first < 0 || last <= first) {
    common::ThrowInvalidInput("emission profile",
                              "covers fewer than two angles with enough signal (" + std::to_string(obs.size()) +
                                  " observations up to " + std::to_string(max_theta) + " degrees)",
                              "the diffuser session needs dots over a range of angles from the screen's normal");
  }
  EmissionProfile& p = fit.profile;
  p.kind = "measured";
  p.step_deg = step;
  p.covered_min_deg = first * step;
  p.covered_max_deg = last * step;
  for (int k = 0; k <= last; ++k) p.table.push_back(std::exp(g(k) - g(0)));
  report.table_std.resize(last + 1);
  report.table_observations.resize(last + 1);
  const auto [n, cos_rms] = FitCosPower(obs, order, runs);
  p.exponent = std::clamp(n, 0.0, 50.0);
  report.cos_power_residual_rms = cos_rms;
  return fit;
}

}  // namespace svbtdf::calib
