#include "svbtdf/simulate/renderer.h"

#include "svbtdf/common/parallel.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <exception>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <thread>

#include "svbtdf/common/error.h"
#include "svbtdf/common/random.h"
#include "svbtdf/model/polarisation.h"

namespace svbtdf::simulate {
namespace {

// A counter-based random stream: SplitMix64 over a key made from (seed, stream, pixel), so that
// the noise of a pixel does not depend on threading or on the order of rendering.
class PixelRandom {
 public:
  PixelRandom(uint64_t seed, uint64_t stream, uint64_t pixel)
      : state_(common::SplitMix64(common::SplitMix64(common::SplitMix64(seed) ^ stream) ^ pixel)) {}

  uint64_t NextBits() { return common::SplitMix64(state_ += 0x9e3779b97f4a7c15ULL); }
  double Uniform() { return common::UnitInterval(NextBits()); }
  double Gaussian() {
    return common::StandardNormal([this] { return NextBits(); });
  }
  // Poisson(mean): exact multiplication method for small means, the normal approximation with
  // the exact variance above 64 electrons (its error is far below the read noise there).
  double Poisson(double mean) {
    if (mean <= 0.0) return 0.0;
    if (mean > 64.0) return std::max(0.0, std::round(mean + std::sqrt(mean) * Gaussian()));
    const double limit = std::exp(-mean);
    double product = Uniform();
    int count = 0;
    while (product > limit) {
      product *= Uniform();
      ++count;
    }
    return count;
  }

 private:
  uint64_t state_;
};

double SrgbEncode(double v) {
  return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
}

// Stratified sub-sample offsets in a pixel, in (-0.5, 0.5).
double SubSample(int k, int n) { return (k + 0.5) / n - 0.5; }

// The undistorted normalised coordinates of the pixel corners (x - 0.5, y), x = 0 .. size - 1,
// each Newton solve started from its left neighbour's answer.
void CornerRow(const PinholeCamera& camera, double y, std::vector<std::optional<model::Vec2>>* row) {
  const model::Vec2* start = nullptr;
  for (size_t x = 0; x < row->size(); ++x) {
    (*row)[x] = camera.ImagePoint(model::Vec2(x - 0.5, y), start);
    start = (*row)[x] ? &*(*row)[x] : nullptr;
  }
}

// Sub-sample (sx, sy) of n x n in the pixel whose corners' normalised coordinates are given
// (top left, top right, bottom left, bottom right). Across one pixel the lens and the
// perspective are linear to far below a thousandth of a pixel, so the corners' points
// interpolate every sub-sample's: one Newton solve a pixel instead of n^2.
template <typename Point>
Point InterpolateInPixel(const std::array<Point, 4>& corners, int sx, int sy, int n) {
  const double fx = SubSample(sx, n) + 0.5, fy = SubSample(sy, n) + 0.5;
  const Point left = (1 - fy) * corners[0] + fy * corners[2];
  const Point right = (1 - fy) * corners[1] + fy * corners[3];
  return (1 - fx) * left + fx * right;
}

}  // namespace


const DiskRule& DotRule(double ratio, double lobe_fraction) {
  // The centre alone.
  static const DiskRule point{{model::Vec2::Zero()}, {1.0}};
  // Stroud's S2:3-1: four points at radius sqrt(1/2) on the axes, weight 1/4 each. The mean of
  // x^2 over the unit disk is 1/4 = r^2 / 2, and the odd moments vanish: exact to degree 3.
  static const DiskRule four = [] {
    DiskRule rule;
    const double r = std::sqrt(0.5);
    rule.nodes = {{r, 0.0}, {0.0, r}, {-r, 0.0}, {0.0, -r}};
    rule.weights.assign(4, 0.25);
    return rule;
  }();
  // Radon's 7-point rule (degree 5): the centre with weight 1/4 and six points at radius
  // sqrt(2/3) with weight 1/8 each.
  static const DiskRule radon = [] {
    DiskRule rule{{model::Vec2::Zero()}, {0.25}};
    const double r = std::sqrt(2.0 / 3.0);
    for (int k = 0; k < 6; ++k) {
      rule.nodes.push_back(r * model::Vec2(std::cos(k * model::kPi / 3), std::sin(k * model::kPi / 3)));
      rule.weights.push_back(0.125);
    }
    return rule;
  }();
  // A product rule: 3 Gauss-Legendre nodes in r^2 (uniform in area) x 8 angles, staggered from
  // ring to ring; exact to degree 7.
  static const DiskRule fine = [] {
    DiskRule rule;
    const double s[3] = {0.5 - 0.5 * std::sqrt(0.6), 0.5, 0.5 + 0.5 * std::sqrt(0.6)};
    const double w[3] = {5.0 / 18, 8.0 / 18, 5.0 / 18};
    for (int ring = 0; ring < 3; ++ring) {
      for (int k = 0; k < 8; ++k) {
        const double phi = (k + 0.5 * ring) * model::kPi / 4;
        rule.nodes.push_back(std::sqrt(s[ring]) * model::Vec2(std::cos(phi), std::sin(phi)));
        rule.weights.push_back(w[ring] / 8);
      }
    }
    return rule;
  }();
  // The ratio at which a rule errs at the peak, relative to the peak, as much as it errs here
  // relative to the value here (renderer.h).
  const double as_at_peak = ratio * std::min(1.0, 2.0 * std::sqrt(std::sqrt(std::clamp(lobe_fraction, 0.0, 1.0))));
  if (as_at_peak < kPointDotRatio) return point;
  if (as_at_peak < kFourPointDotRatio) return four;
  return as_at_peak < kRadonDotRatio ? radon : fine;
}

RigRenderer::RigRenderer(const Rig& rig, const SpatialBtdf* material, int threads)
    : rig_(rig),
      material_(material),
      threads_(threads),
      vignetting_per_r2_(rig.config().sensor.vignetting /
                         (0.25 * (model::Square(rig.config().intrinsics.width) + model::Square(rig.config().intrinsics.height)))) {
  if (material_) {
    const SampleConfig& s = rig_.config().sample;
    if (material_->texels_x() != s.texels_x || material_->texels_y() != s.texels_y) {
      common::ThrowInvalidInput("truth material", "has " + std::to_string(material_->texels_x()) + " x " +
                        std::to_string(material_->texels_y()) + " texels, the rig's sample " +
                        std::to_string(s.texels_x) + " x " + std::to_string(s.texels_y));
    }
    PrecomputeGroups();
    if (rig_.config().monitor.black_level > 0.0) PrecomputeBackground();
  }
}

void RigRenderer::PrecomputeGroups() {
  const CameraIntrinsics& k = rig_.config().intrinsics;
  const int n = rig_.config().pixel_samples;
  std::vector<std::vector<Group>> rows(k.height);
  common::ParallelFor(k.height, threads_, 4, [&](int begin, int end) {
    for (int y = begin; y < end; ++y) {
      std::vector<Group>& out = rows[y];
      for (int x = 0; x < k.width; ++x) {
        // Few texels per pixel: a small linear map keeps the groups in first-hit order.
        std::vector<std::pair<int, std::array<double, 3>>> found;  // texel -> (count, sx, sy)
        for (int sy = 0; sy < n; ++sy) {
          for (int sx = 0; sx < n; ++sx) {
            const model::Vec2 pixel(x + SubSample(sx, n), y + SubSample(sy, n));
            const std::optional<model::Vec3> hit = rig_.SampleHit(pixel);
            if (!hit) continue;
            const auto texel = rig_.TexelAt(*hit);
            const int index = material_->Index((*texel)[0], (*texel)[1]);
            auto it = std::find_if(found.begin(), found.end(),
                                   [&](const auto& f) { return f.first == index; });
            if (it == found.end()) {
              found.push_back({index, {0.0, 0.0, 0.0}});
              it = found.end() - 1;
            }
            it->second[0] += 1.0;
            it->second[1] += hit->x();
            it->second[2] += hit->y();
          }
        }
        for (const auto& [texel, acc] : found) {
          out.push_back(Group{static_cast<uint32_t>(y * k.width + x), static_cast<uint32_t>(texel),
                              static_cast<float>(acc[0] / (n * n)), acc[1] / acc[0],
                              acc[2] / acc[0]});
        }
      }
    }
  });
  row_begin_.assign(k.height + 1, 0);
  size_t total = 0;
  for (int y = 0; y < k.height; ++y) {
    row_begin_[y] = total;
    total += rows[y].size();
  }
  row_begin_[k.height] = total;
  groups_.reserve(total);
  for (auto& row : rows) groups_.insert(groups_.end(), row.begin(), row.end());
}

void RigRenderer::PrecomputeBackground() {
  // The whole active area glows at the black level: integrate it as a grid of patches, each a
  // point emitter at its centre (the monitor is 4+ cm away, patches are a few mm).
  const MonitorConfig& m = rig_.config().monitor;
  const MonitorFrame& frame = rig_.monitor_frame();
  constexpr int kPatchesX = 48, kPatchesY = 32;
  const double patch_w = m.width / kPatchesX, patch_h = m.height / kPatchesY;
  const double patch_intensity = m.white_exitance * m.Luminance(0.0) * patch_w * patch_h;
  const model::Vec3 camera = rig_.camera().Centre();
  const bool polarised = m.polarisation.linear();
  const model::Vec3 field = m.polarisation.FieldDirection(frame);
  background_.assign(groups_.size() * 3, 0.f);
  common::ParallelFor(static_cast<int>(groups_.size()), threads_, 256, [&](int begin, int end) {
    for (int g = begin; g < end; ++g) {
      const Group& group = groups_[g];
      const model::Vec3 x(group.x, group.y, 0.0);
      const model::Vec3 o = (camera - x).normalized();
      model::Vec3 sum = model::Vec3::Zero();
      for (int py = 0; py < kPatchesY; ++py) {
        for (int px = 0; px < kPatchesX; ++px) {
          const model::Vec3 p = frame.PointAt(model::Vec2((px + 0.5) * frame.width_px / kPatchesX, (py + 0.5) * frame.height_px / kPatchesY));
          const model::Vec3 to_light = p - x;
          const double r2 = to_light.squaredNorm();
          const model::Vec3 i = to_light / std::sqrt(r2);
          const double intensity = patch_intensity * m.emission(-frame.normal.dot(i));
          const model::Rgb rgb = polarised ? material_->EvaluatePolarised(group.texel, i, o, model::TransverseField(field, -i))
                                           : material_->Evaluate(group.texel, i, o);
          sum += model::Vec3(rgb[0], rgb[1], rgb[2]) * (std::abs(i.z()) * intensity / r2);
        }
      }
      for (int c = 0; c < 3; ++c) background_[3 * g + c] = static_cast<float>(sum[c]);
    }
  });
}

model::Vec3 RigRenderer::DotRadianceAt(const Dot& dot, const Group& group) const {
  const model::Vec3 x(group.x, group.y, 0.0);
  const model::Vec3 o = (rig_.camera().Centre() - x).normalized();
  const EmissionProfile& profile = rig_.config().monitor.emission;
  const MonitorFrame& frame = rig_.monitor_frame();
  const Polarisation& polarisation = rig_.config().monitor.polarisation;
  const model::Vec3 field = polarisation.linear() ? polarisation.FieldDirection(frame) : model::Vec3::Zero();
  const model::Vec3 to_centre = dot.position - x;
  const double distance = to_centre.norm();
  const double ratio = dot.radius / distance / material_->MinRoughness(group.texel);
  // Most dots light a sharp lobe's tail, where fewer points are as accurate as more are at its
  // peak: the fraction is asked for only where it could change the rule.
  const double fraction = ratio < kPointDotRatio ? 1.0 : material_->LobeFraction(group.texel, to_centre / distance, o);
  const DiskRule& rule = DotRule(ratio, fraction);
  model::Vec3 sum = model::Vec3::Zero();
  for (size_t k = 0; k < rule.nodes.size(); ++k) {
    const model::Vec3 p = dot.position + dot.radius * (rule.nodes[k].x() * frame.right + rule.nodes[k].y() * frame.down);
    const model::Vec3 to_light = p - x;
    const double r2 = to_light.squaredNorm();
    const model::Vec3 i = to_light / std::sqrt(r2);
    const double intensity = dot.intensity * rule.weights[k] * profile(-frame.normal.dot(i));
    // A polarised screen's light reaches x along -i with the transverse part of its field.
    const model::Rgb rgb = polarisation.linear()
                               ? material_->EvaluatePolarised(group.texel, i, o, model::TransverseField(field, -i))
                               : material_->Evaluate(group.texel, i, o);
    sum += model::Vec3(rgb[0], rgb[1], rgb[2]) * (std::abs(i.z()) * intensity / r2);
  }
  return sum;
}

void RigRenderer::RenderDot(const Dot& dot, common::FloatImage* radiance) const {
  if (!material_) common::ThrowInvalidInput("renderer", "dot images need a truth material");
  const CameraIntrinsics& k = rig_.config().intrinsics;
  *radiance = common::FloatImage(k.width, k.height, 3);
  common::ParallelFor(k.height, threads_, 8, [&](int begin, int end) {
    for (size_t g = row_begin_[begin]; g < row_begin_[end]; ++g) {
      const Group& group = groups_[g];
      const model::Vec3 value = group.weight * DotRadianceAt(dot, group);
      float* out = &radiance->pixels[size_t(group.pixel) * 3];
      for (int c = 0; c < 3; ++c) {
        out[c] += static_cast<float>(value[c]) +
                  (background_.empty() ? 0.f : group.weight * background_[3 * g + c]);
      }
    }
  });
}

void RigRenderer::RenderAllDots(common::FloatImage* radiance) const {
  std::vector<int> all(rig_.dots().size());
  for (size_t q = 0; q < all.size(); ++q) all[q] = static_cast<int>(q);
  RenderDotSet(all, radiance);
}

namespace {

// The lit dots bucketed by their centre's monitor pixel into square cells of `cell` pixels, so
// that the dots within cell / 2 pixels of a point lie in the 2 x 2 cells around it: a
// constant-time lookup where scanning the window of cell^2 pixels took most of a fiducial image's
// time.
class DotBuckets {
 public:
  DotBuckets(const std::vector<Dot>& dots, const std::vector<int>& lit, int width_px, int height_px, int cell)
      : cell_(std::max(1, cell)), cols_(width_px / cell_ + 2), rows_(height_px / cell_ + 2), cells_(size_t(cols_) * rows_) {
    for (int q : lit) {
      const Dot& dot = dots.at(q);
      if (const int c = Cell(dot.monitor_x, dot.monitor_y); c >= 0) cells_[c].push_back(&dot);
    }
  }

  // Calls visit(dot) for every lit dot whose centre pixel is within cell / 2 pixels of (ux, uy)
  // along both axes (and perhaps a few farther ones); stops at the first that returns true.
  template <typename Visit>
  bool Any(int ux, int uy, Visit&& visit) const {
    const int cx = Floor(ux - cell_ / 2), cy = Floor(uy - cell_ / 2);
    for (int y = cy; y <= cy + 1; ++y) {
      for (int x = cx; x <= cx + 1; ++x) {
        if (x < 0 || y < 0 || x >= cols_ || y >= rows_) continue;
        for (const Dot* dot : cells_[size_t(y) * cols_ + x]) {
          if (visit(*dot)) return true;
        }
      }
    }
    return false;
  }

 private:
  int Floor(int u) const { return u >= 0 ? u / cell_ : -((-u + cell_ - 1) / cell_); }
  int Cell(int ux, int uy) const {
    const int x = Floor(ux), y = Floor(uy);
    return x >= 0 && y >= 0 && x < cols_ && y < rows_ ? y * cols_ + x : -1;
  }

  int cell_, cols_, rows_;
  std::vector<std::vector<const Dot*>> cells_;
};

}  // namespace

void RigRenderer::RenderDotSet(const std::vector<int>& lit, common::FloatImage* radiance) const {
  const MonitorConfig& m = rig_.config().monitor;
  const MonitorFrame& frame = rig_.monitor_frame();
  const double on = m.white_exitance * m.Luminance(rig_.config().dots.level);
  const double off = m.white_exitance * m.Luminance(0.0);
  // A dot's disk lies within `reach` monitor pixels of its centre pixel.
  const int reach = static_cast<int>(std::ceil(rig_.config().dots.radius_px)) + 1;
  const DotBuckets buckets(rig_.dots(), lit, static_cast<int>(frame.width_px), static_cast<int>(frame.height_px), 2 * reach + 1);
  auto exitance = [&](const model::Vec3& p) -> double {
    const model::Vec2 uv = frame.PixelCoordinates(p);
    if (!frame.InActiveArea(uv)) return 0.0;
    const bool lit_here = buckets.Any(static_cast<int>(uv.x()), static_cast<int>(uv.y()),
                                      [&](const Dot& dot) { return (p - dot.position).norm() <= dot.radius; });
    return lit_here ? on : off;
  };
  RenderMonitor(exitance, radiance);
}

void RigRenderer::RenderFlatField(double level, common::FloatImage* radiance) const {
  const MonitorConfig& m = rig_.config().monitor;
  const MonitorFrame& frame = rig_.monitor_frame();
  const double exitance = m.white_exitance * m.Luminance(level);
  RenderMonitor([&](const model::Vec3& p) { return frame.InActiveArea(frame.PixelCoordinates(p)) ? exitance : 0.0; },
                radiance);
}

void RigRenderer::RenderMonitor(const std::function<double(const model::Vec3&)>& exitance, common::FloatImage* radiance) const {
  const MonitorConfig& m = rig_.config().monitor;
  const MonitorFrame& frame = rig_.monitor_frame();
  const CameraIntrinsics& k = rig_.config().intrinsics;
  const int n = rig_.config().board_samples;
  const PinholeCamera& camera = rig_.camera();
  const model::Vec3 centre = camera.Centre();
  *radiance = common::FloatImage(k.width, k.height, 3);
  common::ParallelFor(k.height, threads_, 4, [&](int begin, int end) {
    std::vector<std::optional<model::Vec2>> top(k.width + 1), bottom(k.width + 1);
    CornerRow(camera, begin - 0.5, &top);
    for (int y = begin; y < end; ++y) {
      CornerRow(camera, y + 0.5, &bottom);
      for (int x = 0; x < k.width; ++x) {
        const bool interpolate = top[x] && top[x + 1] && bottom[x] && bottom[x + 1];
        double sum = 0.0;
        for (int sy = 0; sy < n; ++sy) {
          for (int sx = 0; sx < n; ++sx) {
            const std::optional<model::Vec3> ray =
                interpolate ? camera.RayThrough(InterpolateInPixel<model::Vec2>({*top[x], *top[x + 1], *bottom[x], *bottom[x + 1]}, sx, sy, n))
                            : camera.PixelRay(model::Vec2(x + SubSample(sx, n), y + SubSample(sy, n)));
            if (!ray) continue;
            const std::optional<model::Vec3> p = frame.Intersect(centre, *ray);
            const double cos_e = -frame.normal.dot(*ray);
            if (!p || !(cos_e > 0.0)) continue;
            // Radiance of an emitter of radiant intensity per area I P(theta_e): I P / cos.
            sum += exitance(*p) * m.emission(cos_e) / cos_e;
          }
        }
        for (int c = 0; c < 3; ++c) radiance->at(x, y, c) = static_cast<float>(sum / (n * n));
      }
      std::swap(top, bottom);
    }
  });
}

namespace {

// A uniformly lit chessboard: squares from -1 to inner_cols along x (inner corners where four
// squares meet), a white margin of one square, the table beyond. Every edge of this pattern lies
// on an integer coordinate in square units, so a pixel whose footprint stays within one unit cell
// sees a single reflectance.
class BoardPattern {
 public:
  BoardPattern(const BoardPose& pose, const BoardConfig& board, const model::Vec3& eye)
      : pose_(pose), board_(board), eye_(eye), normal_(pose.rotation.col(2)) {}

  static constexpr double kTable = 0.12;  // reflectance of the table around the board

  // Board coordinates in square units where the ray from the eye meets the board's plane;
  // nullopt when it does not (the table is seen).
  std::optional<model::Vec2> Hit(const std::optional<model::Vec3>& ray) const {
    const double denominator = ray ? normal_.dot(*ray) : 0.0;
    if (std::abs(denominator) < 1e-12) return std::nullopt;
    const double t = normal_.dot(pose_.translation - eye_) / denominator;
    if (t <= 0.0) return std::nullopt;
    const model::Vec3 local = pose_.rotation.transpose() * (eye_ + t * (*ray) - pose_.translation);
    return model::Vec2(local.x(), local.y()) / board_.square;
  }

  double Reflectance(const std::optional<model::Vec2>& uv) const {
    if (!uv) return kTable;
    const double u = uv->x(), v = uv->y();
    if (u < -2.0 || v < -2.0 || u > board_.inner_cols + 1.0 || v > board_.inner_rows + 1.0) return kTable;
    if (u < -1.0 || v < -1.0 || u > board_.inner_cols || v > board_.inner_rows) return board_.reflectance_white;
    const int a = static_cast<int>(std::floor(u)) + static_cast<int>(std::floor(v));
    return (a % 2 == 0) ? board_.reflectance_black : board_.reflectance_white;
  }

  // True when the four corners of a pixel's footprint lie in one unit cell: the cell is convex,
  // so the whole (nearly straight-edged) footprint does.
  static bool OneCell(const std::array<std::optional<model::Vec2>, 4>& corners) {
    for (const auto& c : corners) {
      if (!c) return false;
    }
    const double u = std::floor(corners[0]->x()), v = std::floor(corners[0]->y());
    for (const auto& c : corners) {
      if (std::floor(c->x()) != u || std::floor(c->y()) != v) return false;
    }
    return true;
  }

 private:
  const BoardPose& pose_;
  const BoardConfig& board_;
  model::Vec3 eye_;
  model::Vec3 normal_;
};

}  // namespace

void RigRenderer::RenderZhangBoard(const BoardPose& board, common::FloatImage* radiance) const {
  RenderBoard(board, rig_.config().board, rig_.sensor_camera(), SensorCornerTable(), radiance);
}

void RigRenderer::RenderHolderBoard(const BoardPose& board, common::FloatImage* radiance) const {
  RenderBoard(board, rig_.config().holder_board, rig_.camera(), nullptr, radiance);
}

const std::vector<model::Vec2>* RigRenderer::SensorCornerTable() const {
  const PinholeCamera& camera = rig_.sensor_camera();
  const size_t stride = size_t(camera.intrinsics().width) + 1, rows = size_t(camera.intrinsics().height) + 1;
  if (stride * rows > kMaxCornerTable) return nullptr;
  std::call_once(sensor_corners_once_, [&] {
    sensor_corners_.resize(stride * rows);
    common::ParallelFor(static_cast<int>(rows), threads_, 16, [&](int begin, int end) {
      std::vector<std::optional<model::Vec2>> row(stride);
      for (int y = begin; y < end; ++y) {
        CornerRow(camera, y - 0.5, &row);
        for (size_t x = 0; x < stride; ++x) {
          sensor_corners_[y * stride + x] = row[x].value_or(model::Vec2::Constant(std::numeric_limits<double>::quiet_NaN()));
        }
      }
    });
  });
  return &sensor_corners_;
}

void RigRenderer::RenderBoard(const BoardPose& board, const BoardConfig& config, const PinholeCamera& camera,
                              const std::vector<model::Vec2>* corners, common::FloatImage* radiance) const {
  const CameraIntrinsics& k = camera.intrinsics();
  const int n = rig_.config().board_samples;
  const BoardPattern pattern(board, config, camera.Centre());
  const auto hit = [&](double x, double y) { return pattern.Hit(camera.PixelRay(model::Vec2(x, y))); };
  *radiance = common::FloatImage(k.width, k.height, 3);
  common::ParallelFor(k.height, threads_, 4, [&](int begin, int end) {
    // Board coordinates of the pixel corners above and below the current row.
    std::vector<std::optional<model::Vec2>> points(k.width + 1), top(k.width + 1), bottom(k.width + 1);
    // Corner row r lies at y = r - 0.5.
    const auto corner_hits = [&](int r, std::vector<std::optional<model::Vec2>>* hits) {
      if (corners) {
        const model::Vec2* row = corners->data() + size_t(r) * (k.width + 1);
        for (int x = 0; x <= k.width; ++x) points[x] = row[x].allFinite() ? std::optional(row[x]) : std::nullopt;
      } else {
        CornerRow(camera, r - 0.5, &points);
      }
      for (int x = 0; x <= k.width; ++x) (*hits)[x] = points[x] ? pattern.Hit(camera.RayThrough(*points[x])) : std::nullopt;
    };
    corner_hits(begin, &top);
    for (int y = begin; y < end; ++y) {
      corner_hits(y + 1, &bottom);
      for (int x = 0; x < k.width; ++x) {
        double reflectance = 0.0;
        const std::array<std::optional<model::Vec2>, 4> corners = {top[x], top[x + 1], bottom[x], bottom[x + 1]};
        if (BoardPattern::OneCell(corners)) {
          reflectance = pattern.Reflectance(top[x]);  // the cell's, wherever in it
        } else if (corners[0] && corners[1] && corners[2] && corners[3]) {
          // The sub-samples' board points interpolate the corners' (see InterpolateInPixel).
          const std::array<model::Vec2, 4> board_corners = {*corners[0], *corners[1], *corners[2], *corners[3]};
          for (int sy = 0; sy < n; ++sy) {
            for (int sx = 0; sx < n; ++sx) reflectance += pattern.Reflectance(InterpolateInPixel(board_corners, sx, sy, n));
          }
          reflectance /= n * n;
        } else {
          for (int sy = 0; sy < n; ++sy) {
            for (int sx = 0; sx < n; ++sx) reflectance += pattern.Reflectance(hit(x + SubSample(sx, n), y + SubSample(sy, n)));
          }
          reflectance /= n * n;
        }
        const float value = static_cast<float>(config.illumination * reflectance);
        for (int c = 0; c < 3; ++c) radiance->at(x, y, c) = value;
      }
      std::swap(top, bottom);
    }
  });
}

std::vector<model::Vec3> BoardCorners(const BoardPose& pose, const BoardConfig& board) {
  std::vector<model::Vec3> corners;
  for (int j = 0; j < board.inner_rows; ++j) {
    for (int i = 0; i < board.inner_cols; ++i) corners.push_back(pose.ToWorld(model::Vec2(i, j) * board.square));
  }
  return corners;
}

BoardPose RigRenderer::HolderBoardPose() const {
  const BoardConfig& b = rig_.config().holder_board;
  BoardPose pose;
  // Board x along world x, board y along world -y, so that the board faces the camera (+z) with
  // a right-handed frame whose z points down into the plane: rotation = diag(1, -1, -1).
  pose.rotation = model::Vec3(1.0, -1.0, -1.0).asDiagonal();
  pose.translation = model::Vec3(-(b.inner_cols - 1) * b.square / 2, (b.inner_rows - 1) * b.square / 2, 0.0);
  return pose;
}

std::vector<BoardPose> RigRenderer::ZhangBoardPoses(int views, uint64_t seed) const {
  const BoardConfig& b = rig_.config().board;
  const PinholeCamera& camera = rig_.sensor_camera();
  const CameraIntrinsics& k = camera.intrinsics();
  const CameraPose& camera_pose = camera.pose();
  const double distance = rig_.camera().Centre().norm();
  // The board's outline including its white margin: this much must be in view.
  const std::array<model::Vec2, 4> outline = {model::Vec2(-2, -2) * b.square,
                                       model::Vec2(b.inner_cols + 1, -2) * b.square,
                                       model::Vec2(b.inner_cols + 1, b.inner_rows + 1) * b.square,
                                       model::Vec2(-2, b.inner_rows + 1) * b.square};
  const model::Vec2 board_centre = model::Vec2(b.inner_cols - 1, b.inner_rows - 1) * b.square / 2.0;
  std::vector<BoardPose> poses;
  PixelRandom random(seed, 0x626f617264ULL, 0);
  for (int view = 0; view < views; ++view) {
    bool placed = false;
    for (int attempt = 0; attempt < 200 && !placed; ++attempt) {
      const double shrink = 1.0 - attempt / 200.0;  // fall back toward fronto-parallel, centred
      const double tilt = shrink * (20.0 + 20.0 * random.Uniform()) * model::kPi / 180.0;
      const double axis_angle = model::kTwoPi * (view + 0.3 * random.Uniform()) / views;
      const double spin = shrink * (random.Uniform() - 0.5) * 40.0 * model::kPi / 180.0;
      const model::Vec3 axis(std::cos(axis_angle), std::sin(axis_angle), 0.0);
      // In camera coordinates: the board faces the camera (board z along the optical axis),
      // tilted about an in-plane axis and spun about its normal.
      const model::Mat3 in_camera = Eigen::AngleAxisd(tilt, axis).toRotationMatrix() *
                             Eigen::AngleAxisd(spin, model::Vec3::UnitZ()).toRotationMatrix();
      const model::Vec2 offset_px((random.Uniform() - 0.5) * 0.3 * shrink * k.width,
                           (random.Uniform() - 0.5) * 0.3 * shrink * k.height);
      const double depth = distance * (0.9 + 0.2 * random.Uniform());
      const model::Vec3 centre_cam((k.cx + offset_px.x() - k.cx) / k.fx * depth,
                            (k.cy + offset_px.y() - k.cy) / k.fy * depth, depth);
      BoardPose pose;
      pose.rotation = camera_pose.rotation.transpose() * in_camera;
      const model::Vec3 centre_world = camera_pose.rotation.transpose() * (centre_cam - camera_pose.translation);
      pose.translation = centre_world - pose.rotation * model::Vec3(board_centre.x(), board_centre.y(), 0.0);
      placed = true;
      for (const model::Vec2& corner : outline) {
        const std::optional<model::Vec2> px = camera.Project(pose.ToWorld(corner));
        if (!px || px->x() < 2 || px->y() < 2 || px->x() > k.width - 3 || px->y() > k.height - 3) {
          placed = false;
          break;
        }
      }
      if (placed) poses.push_back(pose);
    }
    if (!placed) {
      common::ThrowInvalidInput("board", "a " + std::to_string(b.inner_cols) + " x " +
                        std::to_string(b.inner_rows) + " board of " +
                        std::to_string(b.square * 1000) + " mm squares does not fit in the camera's view",
                        "use smaller squares (board.square) or a wider sensor (window)");
    }
  }
  return poses;
}

// 1 / (1 + v r^2), r the distance from the principal point over the half diagonal.
double RigRenderer::Vignetting(const model::Vec2& pixel) const {
  const CameraIntrinsics& k = rig_.config().intrinsics;
  return 1.0 / (1.0 + vignetting_per_r2_ * (model::Square(pixel.x() - k.cx) + model::Square(pixel.y() - k.cy)));
}

double RigRenderer::MeanElectrons(double radiance, const model::Vec2& pixel, double exposure_s) const {
  return MeanElectrons(radiance, ElectronsPerRadiance(pixel, exposure_s), exposure_s);
}

double RigRenderer::ElectronsPerRadiance(const model::Vec2& pixel, double exposure_s) const {
  return exposure_s * rig_.config().sensor.sensitivity * Vignetting(pixel);
}

double RigRenderer::MeanElectrons(double radiance, double electrons_per_radiance, double exposure_s) const {
  return radiance * electrons_per_radiance + rig_.config().sensor.dark_current * exposure_s;
}

common::CameraImage RigRenderer::Expose(const common::FloatImage& radiance, double exposure_s, uint64_t seed, uint64_t stream,
                                const model::Vec2& window_origin) const {
  const SensorConfig& s = rig_.config().sensor;
  common::CameraImage out;
  out.width = radiance.width;
  out.height = radiance.height;
  out.channels = radiance.channels;
  out.bits_per_sample = s.bit_depth;
  out.pixels.assign(radiance.pixels.size(), 0);
  const double max_value = std::ldexp(1.0, s.bit_depth) - 1.0;
  const bool srgb = s.response == "srgb";
  common::ParallelFor(radiance.height, threads_, 16, [&](int begin, int end) {
    for (int y = begin; y < end; ++y) {
      for (int x = 0; x < radiance.width; ++x) {
        const uint64_t pixel = uint64_t(y) * radiance.width + x;
        PixelRandom random(seed, stream, pixel);
        const double gain = ElectronsPerRadiance(window_origin + model::Vec2(x, y), exposure_s);  // once per pixel
        for (int c = 0; c < radiance.channels; ++c) {
          const double mean = MeanElectrons(radiance.at(x, y, c), gain, exposure_s);
          double electrons = s.shot_noise ? random.Poisson(mean) : mean;
          electrons += s.read_noise * random.Gaussian();
          const double linear = std::clamp(electrons / s.full_well, 0.0, 1.0);
          const double encoded = (srgb ? SrgbEncode(linear) : linear) + s.black_offset;
          // Round half up (the value is not negative).
          out.pixels[pixel * radiance.channels + c] = static_cast<uint16_t>(std::min(encoded, 1.0) * max_value + 0.5);
        }
      }
    }
  });
  return out;
}

double RigRenderer::ProbePeakRadiance() const {
  if (!material_) common::ThrowInvalidInput("renderer", "the probe needs a truth material");
  // The dot nearest to where the view of the sample centre goes on, straight through it.
  const model::Vec3 camera = rig_.camera().Centre();
  const model::Vec3 straight = rig_.monitor_frame().Intersect(camera, -camera.normalized()).value_or(model::Vec3::Zero());
  const Dot* best = &rig_.dots().front();
  for (const Dot& dot : rig_.dots()) {
    if ((dot.position - straight).norm() < (best->position - straight).norm()) best = &dot;
  }
  common::FloatImage image;
  RenderDot(*best, &image);
  return *std::max_element(image.pixels.begin(), image.pixels.end());
}

}  // namespace svbtdf::simulate
