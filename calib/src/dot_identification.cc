#include "svbtdf/calib/dot_identification.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <limits>

#include <Eigen/Dense>

#include "svbtdf/common/error.h"
#include "svbtdf/model/vec.h"

namespace svbtdf::calib {
namespace {

// A candidate whose fiducial agreement falls short of this is not the displayed pattern: a few
// dots may be misread (a speck, a dot at the edge of the view), not a tenth of them.
constexpr double kMinFiducialAgreement = 0.85;
// The chosen candidate must beat every other by this much: wrong orientations of a fiducial set
// that no symmetry maps onto itself agree on about half of the dots.
constexpr double kMinFiducialMargin = 0.2;
// A declared orientation further than this from the measured one contradicts it (a lab notes a
// quarter turn; the screen is never turned by half of one).
constexpr double kMaxOrientationDisagreementDeg = 30.0;

double Degrees(double radians) { return radians * 180.0 / model::kPi; }

double NormalisedDegrees(double degrees) {
  const double d = std::fmod(degrees, 360.0);
  return d < 0 ? d + 360.0 : d;
}

double AngularDistanceDeg(double a, double b) {
  const double d = NormalisedDegrees(a - b);
  return std::min(d, 360.0 - d);
}

std::string Percent(double fraction) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.0f%%", 100.0 * fraction);
  return buffer;
}

std::string FormatDegrees(double degrees) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.1f", degrees);
  return buffer;
}

// The lattice's direction modulo a quarter turn, from each blob's nearest neighbour: the circular
// mean of four times their angles.
double LatticeAngle(const std::vector<Eigen::Vector2d>& xy) {
  std::complex<double> sum = 0;
  for (size_t i = 0; i < xy.size(); ++i) {
    double best = std::numeric_limits<double>::infinity();
    Eigen::Vector2d to_nearest = Eigen::Vector2d::Zero();
    for (size_t j = 0; j < xy.size(); ++j) {
      const double d = (xy[j] - xy[i]).squaredNorm();
      if (j != i && d < best) best = d, to_nearest = xy[j] - xy[i];
    }
    if (std::isfinite(best)) sum += std::polar(1.0, 4.0 * std::atan2(to_nearest.y(), to_nearest.x()));
  }
  return std::arg(sum) / 4.0;
}

// Monitor metres (u, v) pitch -> the plane's xy.
struct AffineMap {
  Eigen::Matrix2d linear = Eigen::Matrix2d::Identity();
  Eigen::Vector2d offset = Eigen::Vector2d::Zero();
  Eigen::Vector2d operator()(const Eigen::Vector2d& m) const { return linear * m + offset; }
};

AffineMap CandidateMap(double phi, bool mirrored) {
  const Eigen::Matrix2d turn = Eigen::Rotation2Dd(phi).toRotationMatrix();
  AffineMap map;
  map.linear = mirrored ? turn : Eigen::Matrix2d(turn * Eigen::Vector2d(1.0, -1.0).asDiagonal());
  return map;
}

// The least-squares affine map of `from` onto `to`; the old map where too few pairs fix it or
// the fit would change the handedness (which only the candidate decides).
AffineMap FitAffine(const std::vector<Eigen::Vector2d>& from, const std::vector<Eigen::Vector2d>& to,
                    const AffineMap& previous) {
  AffineMap map = previous;
  if (from.size() >= 6) {
    Eigen::MatrixXd a(from.size(), 3);
    Eigen::MatrixXd b(from.size(), 2);
    for (size_t k = 0; k < from.size(); ++k) {
      a.row(k) << from[k].x(), from[k].y(), 1.0;
      b.row(k) = to[k].transpose();
    }
    const Eigen::MatrixXd x = a.colPivHouseholderQr().solve(b);  // 3 x 2
    AffineMap fitted;
    fitted.linear = x.topRows(2).transpose();
    fitted.offset = x.row(2).transpose();
    if (fitted.linear.allFinite() && fitted.linear.determinant() * previous.linear.determinant() > 0) return fitted;
  }
  // A translation: the median of the offsets.
  std::vector<double> dx, dy;
  for (size_t k = 0; k < from.size(); ++k) {
    const Eigen::Vector2d d = to[k] - previous.linear * from[k];
    dx.push_back(d.x());
    dy.push_back(d.y());
  }
  if (dx.empty()) return map;
  std::nth_element(dx.begin(), dx.begin() + dx.size() / 2, dx.end());
  std::nth_element(dy.begin(), dy.begin() + dy.size() / 2, dy.end());
  map.offset = {dx[dx.size() / 2], dy[dy.size() / 2]};
  return map;
}

GridCandidate MatchCandidate(const std::vector<Eigen::Vector2d>& blob_xy, const std::vector<bool>& blob_lit,
                             const DisplayedGrid& grid, double phi, bool mirrored) {
  std::vector<Eigen::Vector2d> dot_m;  // the dots in monitor metres
  Eigen::Vector2d dot_mean = Eigen::Vector2d::Zero(), blob_mean = Eigen::Vector2d::Zero();
  for (const Eigen::Vector2d& px : grid.monitor_px) dot_m.push_back(px * grid.pixel_pitch_m), dot_mean += dot_m.back();
  for (const Eigen::Vector2d& b : blob_xy) blob_mean += b;
  AffineMap map = CandidateMap(phi, mirrored);
  map.offset = blob_mean / blob_xy.size() - map.linear * dot_mean / dot_m.size();
  GridCandidate c;
  c.mirrored = mirrored;
  c.blob_of_dot.assign(dot_m.size(), -1);
  // Match near the centre first and let the fitted map carry the match outward.
  for (double tolerance : {0.5, 0.4, 0.33, 0.33, 0.33}) {
    std::vector<Eigen::Vector2d> from, to;
    for (size_t q = 0; q < dot_m.size(); ++q) {
      const Eigen::Vector2d predicted = map(dot_m[q]);
      double best = tolerance * grid.spacing_m;
      c.blob_of_dot[q] = -1;
      for (size_t b = 0; b < blob_xy.size(); ++b) {
        const double d = (blob_xy[b] - predicted).norm();
        if (d < best) best = d, c.blob_of_dot[q] = static_cast<int>(b);
      }
      if (c.blob_of_dot[q] >= 0) from.push_back(dot_m[q]), to.push_back(blob_xy[c.blob_of_dot[q]]);
    }
    map = FitAffine(from, to, map);
  }
  double sum = 0;
  int agree = 0;
  for (size_t q = 0; q < dot_m.size(); ++q) {
    const int b = c.blob_of_dot[q];
    if (b < 0) continue;
    ++c.matched;
    sum += (blob_xy[b] - map(dot_m[q])).squaredNorm();
    if (!grid.fiducial.empty() && !blob_lit.empty()) agree += grid.fiducial[q] == blob_lit[b];
  }
  c.rms_m = c.matched > 0 ? std::sqrt(sum / c.matched) : std::numeric_limits<double>::infinity();
  if (!grid.fiducial.empty() && !blob_lit.empty() && c.matched > 0) c.fiducial_agreement = double(agree) / c.matched;
  // The direction of the screen's u axis as fitted.
  c.orientation_deg = NormalisedDegrees(Degrees(std::atan2(map.linear(1, 0), map.linear(0, 0))));
  return c;
}

}  // namespace

std::vector<GridCandidate> MatchGridCandidates(const std::vector<Eigen::Vector2d>& blob_xy,
                                               const std::vector<bool>& blob_lit, const DisplayedGrid& grid) {
  std::vector<GridCandidate> candidates;
  if (blob_xy.empty() || grid.monitor_px.empty()) return candidates;
  const double lattice = LatticeAngle(blob_xy);
  for (bool mirrored : {false, true}) {
    for (int quarter = 0; quarter < 4; ++quarter) {
      candidates.push_back(MatchCandidate(blob_xy, blob_lit, grid, lattice + quarter * model::kPi / 2.0, mirrored));
    }
  }
  std::stable_sort(candidates.begin(), candidates.end(), [](const GridCandidate& a, const GridCandidate& b) {
    if (a.matched != b.matched) return a.matched > b.matched;
    return a.fiducial_agreement > b.fiducial_agreement;
  });
  return candidates;
}

DotIdentification IdentifyDots(const std::vector<Eigen::Vector2d>& blob_xy, const std::vector<bool>& blob_lit,
                               const DisplayedGrid& grid, std::optional<double> declared_orientation_deg,
                               const std::string& source) {
  const std::vector<GridCandidate> candidates = MatchGridCandidates(blob_xy, blob_lit, grid);
  DotIdentification id;
  if (candidates.empty()) {
    id.chosen.blob_of_dot.assign(grid.monitor_px.size(), -1);
    return id;
  }
  // The candidates the blobs alone cannot tell from the best: the grid's symmetries.
  std::vector<GridCandidate> viable;
  for (const GridCandidate& c : candidates) {
    if (c.matched >= 0.9 * candidates.front().matched) viable.push_back(c);
  }
  const bool have_fiducials = !grid.fiducial.empty() && !blob_lit.empty();
  if (have_fiducials) {
    std::stable_sort(viable.begin(), viable.end(), [](const GridCandidate& a, const GridCandidate& b) {
      return a.fiducial_agreement > b.fiducial_agreement;
    });
    id.chosen = viable.front();
    id.identified_by = "fiducials";
    if (viable.size() > 1) id.runner_up_agreement = viable[1].fiducial_agreement;
    if (id.chosen.fiducial_agreement < kMinFiducialAgreement) {
      common::ThrowFormatError(source, "lights dots that match no way the grid can lie (at best " +
                                   Percent(id.chosen.fiducial_agreement) + " of the dots agree)",
                       "check rig.dots.fiducials against what the display showed, and that nothing moved between the "
                       "all-dots and the fiducial captures");
    }
    if (id.runner_up_agreement > id.chosen.fiducial_agreement - kMinFiducialMargin) {
      common::ThrowFormatError(source, "cannot tell which way the grid lies: " + Percent(id.chosen.fiducial_agreement) +
                                   " of the dots agree with one orientation and " + Percent(id.runner_up_agreement) +
                                   " with another",
                       "light fiducial dots that no turn or mirror of the grid maps onto themselves");
    }
    if (id.chosen.mirrored) {
      common::ThrowFormatError(source, "shows the dot grid mirrored: seen from the sample, the screen's pixel axes run right "
                               "and up instead of right and down, which no monitor seen from its front does "
                               "(the dots would all be given the wrong positions)",
                       "turn off the display's mirror or flip mode, or check that rig.dots.positions_px are the "
                       "screen's own pixel coordinates (x right, y down)");
    }
    if (declared_orientation_deg &&
        AngularDistanceDeg(id.chosen.orientation_deg, *declared_orientation_deg) > kMaxOrientationDisagreementDeg) {
      common::ThrowFormatError(source, "shows the screen turned by " + FormatDegrees(id.chosen.orientation_deg) +
                                   " degrees, but rig.monitor.orientation_deg says " +
                                   FormatDegrees(*declared_orientation_deg),
                       "check how the monitor lies and correct rig.monitor.orientation_deg (or remove it)");
    }
    return id;
  }
  if (!declared_orientation_deg) {
    common::ThrowFormatError(source, "has no fiducial capture and no rig.monitor.orientation_deg: a dot grid looks the same "
                             "turned by half a turn, so which blob is which dot cannot be told",
                     "capture fiducials/e0 (svbtdf acquire plans it), or state the screen's orientation in "
                     "rig.monitor.orientation_deg (docs/calibration-format.md)");
  }
  const GridCandidate* nearest = nullptr;
  for (const GridCandidate& c : viable) {
    if (c.mirrored) continue;
    if (!nearest || AngularDistanceDeg(c.orientation_deg, *declared_orientation_deg) <
                        AngularDistanceDeg(nearest->orientation_deg, *declared_orientation_deg)) {
      nearest = &c;
    }
  }
  if (!nearest ||
      AngularDistanceDeg(nearest->orientation_deg, *declared_orientation_deg) > kMaxOrientationDisagreementDeg) {
    common::ThrowFormatError(source, "shows no dot grid turned by about rig.monitor.orientation_deg = " +
                                 FormatDegrees(*declared_orientation_deg) + " degrees",
                     "check how the monitor lies, or capture fiducials/e0");
  }
  id.chosen = *nearest;
  id.identified_by = "declared orientation";
  return id;
}

}  // namespace svbtdf::calib
