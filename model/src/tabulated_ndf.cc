#include "svbtdf/model/tabulated_ndf.h"

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cmath>
#include <string>

#include "svbtdf/common/error.h"
#include "svbtdf/common/random.h"

namespace svbtdf::model {
namespace {

constexpr int kSubCells = 4;        // quadrature points per cell side for the integrals
constexpr int kAreaThetaSteps = 64; // projected-area table over the direction of v
constexpr int kAreaPhiSteps = 64;

// Quadrature nodes of the hemicube: directions and solid-angle weights, kSubCells^2 per cell.
struct Quadrature {
  std::vector<Vec3> directions;
  std::vector<double> weights;
};

Quadrature CellQuadrature(const Hemicube& grid, int sub) {
  Quadrature q;
  q.directions.reserve(static_cast<size_t>(grid.num_cells()) * sub * sub);
  for (int c = 0; c < grid.num_cells(); ++c) {
    // Sub-cell solid angles are proportional to 1/r^3 on the face plane; normalise them to the
    // cell's exact solid angle.
    const size_t first = q.directions.size();
    double total = 0;
    for (int a = 0; a < sub; ++a) {
      for (int b = 0; b < sub; ++b) {
        const Vec3 d = grid.CellPoint(c, (a + 0.5) / sub, (b + 0.5) / sub);
        // |dω/dA| on a unit-distance plane is cos^3 of the angle to the plane's normal, i.e.
        // the cube of the direction's largest component.
        const double dominant = std::max({std::abs(d.x()), std::abs(d.y()), d.z()});
        const double w = dominant * dominant * dominant;
        q.directions.push_back(d);
        q.weights.push_back(w);
        total += w;
      }
    }
    for (size_t k = first; k < q.directions.size(); ++k) q.weights[k] *= grid.CellSolidAngle(c) / total;
  }
  return q;
}

}  // namespace

struct TabulatedNdf::AreaTable {
  std::vector<double> area;  // (kAreaThetaSteps + 1) x kAreaPhiSteps, theta in [0, pi/2]
  double At(const Vec3& v) const {
    const double theta = std::acos(std::clamp(v.z(), 0.0, 1.0));
    double phi = std::atan2(v.y(), v.x());
    if (phi < 0) phi += kTwoPi;
    const double t = theta / (0.5 * kPi) * kAreaThetaSteps;
    const double p = phi / kTwoPi * kAreaPhiSteps;
    const int t0 = std::min(static_cast<int>(t), kAreaThetaSteps - 1);
    const int p0 = static_cast<int>(p) % kAreaPhiSteps;
    const int p1 = (p0 + 1) % kAreaPhiSteps;
    const double ft = t - t0, fp = p - std::floor(p);
    const auto a = [&](int ti, int pi) { return area[static_cast<size_t>(ti) * kAreaPhiSteps + pi]; };
    return (1 - ft) * ((1 - fp) * a(t0, p0) + fp * a(t0, p1)) + ft * ((1 - fp) * a(t0 + 1, p0) + fp * a(t0 + 1, p1));
  }
};

TabulatedNdf::TabulatedNdf(const Hemicube& grid, std::vector<double> ln_d) : grid_(grid), ln_d_(std::move(ln_d)) {
  if (static_cast<int>(ln_d_.size()) != grid_.num_cells()) {
    common::ThrowInvalidInput("tabulated NDF", "has " + std::to_string(ln_d_.size()) + " values for " +
                                           std::to_string(grid_.num_cells()) + " hemicube cells");
  }
  for (double value : ln_d_) {
    if (!std::isfinite(value)) common::ThrowInvalidInput("tabulated NDF", "holds a non-finite ln D value");
  }
}

TabulatedNdf::TabulatedNdf(const Hemicube& grid, const Ndf& ndf) : grid_(grid), ln_d_(grid.num_cells()) {
  for (int c = 0; c < grid_.num_cells(); ++c) {
    const double d = ndf.D(grid_.CellCenter(c));
    ln_d_[c] = d > 0 ? std::max(std::log(d), -700.0) : -700.0;
  }
}

TabulatedNdf::TabulatedNdf(const TabulatedNdf& other) : grid_(other.grid_), ln_d_(other.ln_d_) {}

double TabulatedNdf::D(const Vec3& h) const {
  if (h.z() <= 0) return 0.0;
  double ln = 0;
  for (const auto& [cell, w] : grid_.Interpolation(h)) ln += w * ln_d_[cell];
  return std::exp(ln);
}

double TabulatedNdf::ProjectedIntegral() const {
  // The nodes, their interpolation weights and h.z w depend only on the resolution; fits and
  // material evaluation normalise many thousands of tables of one size (the refinement two per
  // texel), so only the interpolation of ln D and its exp are left, and the loop over the nodes
  // is arranged for the fewest loads: the nodes are grouped by the four cells they interpolate
  // (a quarter of a cell's nodes share them), so each group reads its four ln D once and each
  // node only its own four weights. Single precision throughout (ln D relative to its largest,
  // a table that stays in L1; Eigen's vectorised exp over all nodes at once): each node is good
  // to about 1e-7 relative and their sum, accumulated in double, as well, far below the table's
  // own interpolation error.
  struct Nodes {
    int resolution = 0;
    std::vector<std::array<int32_t, 4>> group_cells;
    std::vector<int32_t> group_end;              // one past each group's last node
    std::vector<std::array<float, 4>> weight;    // per node, in its group's cell order
    Eigen::ArrayXf projected_weight;
    std::vector<float> table;  // scratch: ln D per cell, relative to its largest
    Eigen::ArrayXf ln_d;       // scratch: the same at each node, then its term exp(ln D) h.z w
  };
  static thread_local Nodes nodes;
  if (nodes.resolution != grid_.resolution()) {
    const Quadrature quadrature = CellQuadrature(grid_, kSubCells);
    struct Node {
      std::array<int32_t, 4> cells;
      std::array<float, 4> weights;
      float projected_weight;
    };
    std::vector<Node> list;
    for (size_t k = 0; k < quadrature.directions.size(); ++k) {
      if (quadrature.directions[k].z() <= 0) continue;  // D is 0 there
      const Hemicube::Weights interpolation = grid_.Interpolation(quadrature.directions[k]);
      Node node;
      for (int i = 0; i < 4; ++i) {
        node.cells[i] = interpolation[i].first;
        node.weights[i] = static_cast<float>(interpolation[i].second);
      }
      node.projected_weight = static_cast<float>(quadrature.directions[k].z() * quadrature.weights[k]);
      list.push_back(node);
    }
    std::stable_sort(list.begin(), list.end(), [](const Node& a, const Node& b) { return a.cells < b.cells; });
    nodes.group_cells.clear();
    nodes.group_end.clear();
    nodes.weight.resize(list.size());
    nodes.projected_weight.resize(static_cast<Eigen::Index>(list.size()));
    for (size_t k = 0; k < list.size(); ++k) {
      if (k == 0 || list[k].cells != list[k - 1].cells) {
        if (k > 0) nodes.group_end.push_back(static_cast<int32_t>(k));
        nodes.group_cells.push_back(list[k].cells);
      }
      nodes.weight[k] = list[k].weights;
      nodes.projected_weight[static_cast<Eigen::Index>(k)] = list[k].projected_weight;
    }
    nodes.group_end.push_back(static_cast<int32_t>(list.size()));
    nodes.ln_d.resize(static_cast<Eigen::Index>(list.size()));
    nodes.resolution = grid_.resolution();
  }
  // Relative to the largest ln D, so that no table (however dark or sharp) leaves float's range.
  const double shift = ln_d_.empty() ? 0.0 : *std::max_element(ln_d_.begin(), ln_d_.end());
  nodes.table.resize(ln_d_.size());
  for (size_t c = 0; c < ln_d_.size(); ++c) nodes.table[c] = static_cast<float>(ln_d_[c] - shift);
  float* ln = nodes.ln_d.data();
  int32_t k = 0;
  for (size_t g = 0; g < nodes.group_cells.size(); ++g) {
    const std::array<int32_t, 4>& cells = nodes.group_cells[g];
    const float v0 = nodes.table[cells[0]], v1 = nodes.table[cells[1]], v2 = nodes.table[cells[2]],
                v3 = nodes.table[cells[3]];
    for (; k < nodes.group_end[g]; ++k) {
      const std::array<float, 4>& w = nodes.weight[k];
      ln[k] = w[0] * v0 + w[1] * v1 + w[2] * v2 + w[3] * v3;
    }
  }
  // Evaluated into floats first: fused with the cast to double, Eigen falls back to scalar expf.
  nodes.ln_d = nodes.ln_d.exp() * nodes.projected_weight;
  // Summed in double over eight independent partial sums: one running sum waits on each
  // addition's latency, a quarter of the whole call.
  const float* term = nodes.ln_d.data();
  const Eigen::Index n = nodes.ln_d.size();
  double partial[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  Eigen::Index k8 = 0;
  for (; k8 + 8 <= n; k8 += 8) {
    for (int lane = 0; lane < 8; ++lane) partial[lane] += term[k8 + lane];
  }
  for (; k8 < n; ++k8) partial[0] += term[k8];
  double sum = 0;
  for (double p : partial) sum += p;
  return std::exp(shift) * sum;
}

double TabulatedNdf::Normalize() {
  const double integral = ProjectedIntegral();
  if (!(integral > 0) || !std::isfinite(integral)) {
    throw common::Error(common::ErrorKind::kNumerical, "tabulated NDF", "cannot be normalised (its integral is " +
                                                           std::to_string(integral) + ")");
  }
  const double shift = std::log(integral);
  for (double& value : ln_d_) value -= shift;
  // The projected areas and the sampling bounds scale too; drop the cached tables.
  areas_.Reset();
  sampling_.Reset();
  return integral;
}

const TabulatedNdf::AreaTable& TabulatedNdf::Areas() const {
  return areas_.Get([this] {
    auto table = std::make_shared<AreaTable>();
    // The quadrature nodes in separate arrays (x, y, z and D times the weight), so that the inner
    // loop over them vectorises: a renderer builds this table for every representative of a
    // material (3,600 at paper scale), and it is most of the cost of a first render.
    const Quadrature q = CellQuadrature(grid_, 2);
    const size_t n = q.directions.size();
    // Single precision: four lanes per SSE instruction, and a projected area to about 1e-6
    // relative, far below the table's interpolation error.
    std::vector<float> x(n), y(n), z(n), d_weight(n);
    for (size_t k = 0; k < n; ++k) {
      x[k] = static_cast<float>(q.directions[k].x());
      y[k] = static_cast<float>(q.directions[k].y());
      z[k] = static_cast<float>(q.directions[k].z());
      d_weight[k] = static_cast<float>(D(q.directions[k]) * q.weights[k]);
    }
    table->area.resize(static_cast<size_t>(kAreaThetaSteps + 1) * kAreaPhiSteps);
    for (int t = 0; t <= kAreaThetaSteps; ++t) {
      const double theta = std::min(0.5 * kPi * t / kAreaThetaSteps, 0.5 * kPi - 1e-6);
      for (int p = 0; p < kAreaPhiSteps; ++p) {
        const Vec3 v = SphericalDirection(theta, kTwoPi * p / kAreaPhiSteps);
        const float vx = static_cast<float>(v.x()), vy = static_cast<float>(v.y()), vz = static_cast<float>(v.z());
        // Eight partial sums: without them the compiler may not reorder the additions to vectorise.
        float partial[8] = {0, 0, 0, 0, 0, 0, 0, 0};
        size_t k = 0;
        for (; k + 8 <= n; k += 8) {
          for (int lane = 0; lane < 8; ++lane) {
            const size_t j = k + lane;
            partial[lane] += std::max(0.0f, vx * x[j] + vy * y[j] + vz * z[j]) * d_weight[j];
          }
        }
        for (; k < n; ++k) partial[0] += std::max(0.0f, vx * x[k] + vy * y[k] + vz * z[k]) * d_weight[k];
        double area = 0;
        for (float value : partial) area += value;
        table->area[static_cast<size_t>(t) * kAreaPhiSteps + p] = area;
      }
    }
    return table;
  });
}

// The proposal of SampleVisibleNormal: a cell with probability proportional to `bound`, then a
// point uniform on the cell's face rectangle (every cell has the face-plane area (2/N)^2). The
// target in face-plane area measure is max(0, v.h) D(h) |dω/dA|, and bound[c] is at least that
// for every v: the largest D the cell's interpolation can reach (the largest ln D two cells
// around), times cos <= 1 and |dω/dA| <= 1.
struct TabulatedNdf::SamplingTable {
  std::vector<double> bound;
  std::vector<double> cumulative;
};

const TabulatedNdf::SamplingTable& TabulatedNdf::Sampling() const {
  return sampling_.Get([this] {
    auto table = std::make_shared<SamplingTable>();
    const int cells = grid_.num_cells();
    table->bound.resize(cells);
    table->cumulative.resize(cells);
    double total = 0;
    for (int c = 0; c < cells; ++c) {
      double max_ln = ln_d_[c];
      for (int nb : grid_.Neighbours(c)) {
        if (nb < 0) continue;
        max_ln = std::max(max_ln, ln_d_[nb]);
        for (int nb2 : grid_.Neighbours(nb)) {
          if (nb2 >= 0) max_ln = std::max(max_ln, ln_d_[nb2]);
        }
      }
      table->bound[c] = std::exp(max_ln);
      total += table->bound[c];
      table->cumulative[c] = total;
    }
    return table;
  });
}

double TabulatedNdf::ProjectedArea(const Vec3& v) const { return Areas().At(v); }

double TabulatedNdf::G1(const Vec3& v, const Vec3& h) const {
  const Vec3 side_adjusted = v.z() < 0 ? Vec3(-v) : v;
  if (side_adjusted.dot(h) <= 0 || side_adjusted.z() <= 0) return 0.0;
  const double area = ProjectedArea(side_adjusted);
  return area > 0 ? std::min(1.0, side_adjusted.z() / area) : 1.0;
}

double TabulatedNdf::VisibleNormalPdf(const Vec3& v, const Vec3& h) const {
  if (v.z() <= 0 || h.z() <= 0) return 0.0;
  const double area = ProjectedArea(v);
  return area > 0 ? std::max(0.0, v.dot(h)) * D(h) / area : 0.0;
}

NormalSample TabulatedNdf::SampleVisibleNormal(const Vec3& v, const Vec2& u) const {
  const SamplingTable& table = Sampling();
  const std::vector<double>& cumulative = table.cumulative;
  const double total = cumulative.back();
  // Rejection needs more than two random numbers: a stream seeded from u keeps the sampler a
  // deterministic function of u, as the interface promises.
  common::Pcg32 rng(static_cast<uint64_t>(u.x() * 9007199254740992.0),
                    static_cast<uint64_t>(u.y() * 9007199254740992.0));
  for (int attempt = 0; attempt < 100000; ++attempt) {
    const double pick = rng.NextDouble() * total;
    const auto cell = static_cast<int>(std::upper_bound(cumulative.begin(), cumulative.end(), pick) - cumulative.begin());
    if (cell >= static_cast<int>(cumulative.size())) continue;
    const double fu = rng.NextDouble(), fv = rng.NextDouble();
    const Vec3 h = grid_.CellPoint(cell, fu, fv);
    const double dominant = std::max({std::abs(h.x()), std::abs(h.y()), h.z()});
    const double cosine = v.dot(h);
    if (cosine <= 0) continue;
    const double target = cosine * D(h) * dominant * dominant * dominant;
    if (rng.NextDouble() * table.bound[cell] <= target) {
      const double pdf = VisibleNormalPdf(v, h);
      const double weight = pdf > 0 ? G1(v, h) * cosine * D(h) / (v.z() * pdf) : 0.0;
      return {h, pdf, weight};
    }
  }
  throw common::Error(common::ErrorKind::kNumerical, "tabulated NDF", "visible-normal sampling did not accept a sample");
}

}  // namespace svbtdf::model
