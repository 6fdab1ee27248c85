#pragma once
// The rig's renderer (docs/simulator.md, "Rendering"): radiance images of every capture a real
// session makes (dot images through the sample, the all-dots image and a flat white without it,
// chessboard views, dark frames) and the camera's sensor chain that turns them into stored values.
//
// A dot image follows the measurement equation of the notes ("Measurement to BTDF"): a pixel that
// sees sample point x records the radiance
//     L(x) = sum over the dot's area elements of R(x, i, o) |i.z| dI(i) / |p - x|^2,
// i = (p - x)/|p - x|, o toward the camera, dI the element's radiant intensity toward x (with the
// monitor's angular profile). Quadrature: per pixel, n x n stratified sub-samples are grouped by
// the texel they hit and each group is evaluated once at the centroid of its sub-samples with
// weight (group size)/n^2; the dot's disk is integrated with the cheapest rule that is accurate
// for the ratio of its angular radius to the texel's smallest NDF roughness, and for how far into
// the lobe's tail the dot lies (DotRule).

#include <cstdint>
#include <functional>
#include <mutex>
#include <vector>

#include "svbtdf/simulate/rig.h"
#include "svbtdf/common/image_io.h"
#include "svbtdf/simulate/spatial_btdf.h"

namespace svbtdf::simulate {

// Where a chessboard is: board point (bx, by, 0) maps to world rotation * b + translation.
// Inner corner (i, j) is at board point (i * square, j * square).
struct BoardPose {
  model::Mat3 rotation = model::Mat3::Identity();
  model::Vec3 translation = model::Vec3::Zero();
  model::Vec3 ToWorld(const model::Vec2& b) const { return rotation * model::Vec3(b.x(), b.y(), 0.0) + translation; }
};

// Inner corners of a board in world coordinates, row-major (i fastest), as OpenCV's finder orders
// them for a board that is not rotated by more than 90 degrees in the image.
std::vector<model::Vec3> BoardCorners(const BoardPose& pose, const BoardConfig& board);

// A cubature rule on the unit disk whose weights sum to 1: it averages a function over the disk.
struct DiskRule {
  std::vector<model::Vec2> nodes;
  std::vector<double> weights;
};

// The rule for a dot whose angular radius is `ratio` times the texel's smallest NDF roughness
// (docs/simulator.md, "Quadrature"): its centre below kPointDotRatio, Stroud's 4-point degree-3
// rule below kFourPointDotRatio, Radon's 7-point degree-5 rule below kRadonDotRatio, else a
// 24-point product rule of degree 7. The bounds keep the error below 1e-3 of the lobe's peak
// (measured: tests/simulate, RigRenderer.DotRulesAreAccurateWhereTheyAreUsed).
//
// `lobe_fraction` (SpatialBtdf::LobeFraction at the dot's centre): in a GGX lobe's tail, where it
// is a fraction F of its peak, each rule's error relative to the value there is about its error at
// the peak, relative to the peak, for a dot F^(1/4) times as large (in the lobe's stretched slope
// space u, D ~ (1 + u^2)^-2 = F and its (d + 1)-th derivatives, which a rule of degree d misses,
// fall as (1 + u^2)^-(5 + d) / 2). So the rule is chosen there by min(1, 2 F^(1/4)) times the
// ratio, the 2 a margin for the derivatives' constants (RigRenderer.DotRulesStayAccurateInTheLobesTail).
inline constexpr double kPointDotRatio = 0.015;
inline constexpr double kFourPointDotRatio = 0.12;
inline constexpr double kRadonDotRatio = 0.22;
const DiskRule& DotRule(double ratio, double lobe_fraction = 1.0);

class RigRenderer {
 public:
  // `material` (the truth: analytic or Monte Carlo) may be null when only captures without the
  // sample are rendered; it must outlive the renderer. threads = 0: all.
  RigRenderer(const Rig& rig, const SpatialBtdf* material, int threads = 0);

  const Rig& rig() const { return rig_; }

  // Radiance of dot `dot` seen through the sample; 0 where the ray misses the sample (the holder
  // is opaque). Includes the monitor's black-level glow when black_level > 0.
  void RenderDot(const Dot& dot, common::FloatImage* radiance) const;

  // The monitor seen directly (sample and holder removed): every dot lit, the dots `lit` (grid
  // indices) at once, or a flat field of `level` over the whole active area. Anti-aliased with
  // board_samples^2 sub-samples.
  void RenderAllDots(common::FloatImage* radiance) const;
  void RenderDotSet(const std::vector<int>& lit, common::FloatImage* radiance) const;
  void RenderFlatField(double level, common::FloatImage* radiance) const;

  // A chessboard lit uniformly: a Zhang view (the rig's `board`) as a whole-sensor image, or the
  // board in the sample holder (`holder_board`) through the window; both through the lens with its
  // distortion. Pixels that straddle a square's edge get board_samples^2 sub-samples.
  void RenderZhangBoard(const BoardPose& board, common::FloatImage* radiance) const;
  void RenderHolderBoard(const BoardPose& board, common::FloatImage* radiance) const;
  // `views` deterministic poses of the Zhang board, tilted 20-40 degrees about varied axes, at
  // about the sample's distance, fully in the sensor's view. Throws when the board cannot fit.
  std::vector<BoardPose> ZhangBoardPoses(int views, uint64_t seed) const;
  // The holder board lying in the sample plane, centred on the sample.
  BoardPose HolderBoardPose() const;

  // The sensor chain: radiance x exposure x sensitivity x vignetting (+ dark current) electrons,
  // Poisson shot noise, Gaussian read noise, full-well clipping, response curve, black offset,
  // quantisation. Noise is a deterministic function of (seed, stream, pixel). `window_origin`:
  // where the image's pixel (0, 0) lies in the window's pixel coordinates (minus the window's
  // offset for a whole-sensor image), for the vignetting.
  common::CameraImage Expose(const common::FloatImage& radiance, double exposure_s, uint64_t seed, uint64_t stream,
                     const model::Vec2& window_origin = model::Vec2::Zero()) const;
  // The noise-free, unquantised, unclipped value on the stored scale (for tests and for the
  // inversion of the chain): (electrons / full_well), before the response curve.
  double MeanElectrons(double radiance, const model::Vec2& pixel, double exposure_s) const;
  double Vignetting(const model::Vec2& pixel) const;

  // Number of pixel groups shaded per dot image (pixels seeing the sample, split by texel).
  size_t num_shaded_groups() const { return groups_.size(); }
  // The largest radiance of dot images, estimated on the dot closest to straight-through.
  double ProbePeakRadiance() const;

 private:
  struct Group {
    uint32_t pixel;   // y * width + x
    uint32_t texel;
    float weight;     // fraction of the pixel's sub-samples in this texel
    double x, y;      // centroid of those sub-samples on the sample plane
  };
  // `corners`, when not null: the camera's CornerTable, else each row's corners are solved.
  void RenderBoard(const BoardPose& board, const BoardConfig& config, const PinholeCamera& camera,
                   const std::vector<model::Vec2>* corners, common::FloatImage* radiance) const;
  // The undistorted normalised coordinates of every pixel corner (x - 0.5, y - 0.5) of the whole
  // sensor, row-major with width + 1 a row (NaN where the distortion cannot be inverted), made on
  // first use and shared by every Zhang view: one Newton solve a corner per session, not per
  // view. Null for a sensor of more than kMaxCornerTable corners (a paper-scale camera: there
  // the 384 MB it would take is worth more than the minute of solves it would save).
  const std::vector<model::Vec2>* SensorCornerTable() const;
  static constexpr size_t kMaxCornerTable = size_t{1} << 22;

  double ElectronsPerRadiance(const model::Vec2& pixel, double exposure_s) const;
  double MeanElectrons(double radiance, double electrons_per_radiance, double exposure_s) const;
  void PrecomputeGroups();
  void PrecomputeBackground();
  model::Vec3 DotRadianceAt(const Dot& dot, const Group& group) const;
  // The monitor seen directly, emitting `exitance(p)` (radiant intensity per area along its
  // normal) at each point p of the screen.
  void RenderMonitor(const std::function<double(const model::Vec3&)>& exitance, common::FloatImage* radiance) const;

  const Rig& rig_;
  const SpatialBtdf* material_;
  int threads_;
  double vignetting_per_r2_;  // the vignetting coefficient over the squared half diagonal
  std::vector<Group> groups_;
  std::vector<size_t> row_begin_;         // groups_ index of each image row's first group
  mutable std::once_flag sensor_corners_once_;
  mutable std::vector<model::Vec2> sensor_corners_;
  std::vector<float> background_;         // black-level glow per group (RGB), when enabled
};

}  // namespace svbtdf::simulate
