// Which blob is which dot, on blobs placed from first principles: a physical screen lying in each
// of the four ways a lab may put it down, described by its top-left corner and its right and down
// vectors in the sample plane as seen from the camera's side. Nothing here uses the simulator.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <set>

#include <Eigen/Geometry>

#include "svbtdf/calib/dot_identification.h"
#include "svbtdf/common/error.h"
#include "svbtdf/session/fiducials.h"

namespace svbtdf::calib {
namespace {

constexpr double kPitch = 0.00025;  // m per monitor pixel

// A screen seen from the sample: where its pixel (0, 0) corner lies and which way its pixel x
// (right) and y (down) axes run in the sample plane. A physical screen seen from its front has
// right x down pointing into the screen, i.e. right, down form a left-handed pair in the plane
// seen from +z: down is right turned clockwise.
struct Screen {
  double orientation_deg;
  Eigen::Vector2d corner, right, down;
};

const Screen kScreens[] = {
    {0, {-0.15, 0.14}, {1, 0}, {0, -1}},    // u along +x, the top edge toward +y
    {90, {0.10, -0.11}, {0, 1}, {1, 0}},    // u along +y, v along +x
    {180, {0.15, -0.06}, {-1, 0}, {0, 1}},  // u along -x, v along +y
    {270, {-0.10, 0.19}, {0, -1}, {-1, 0}}, // u along -y, v along -x
};

struct Scene {
  DisplayedGrid grid;
  std::vector<Eigen::Vector2d> blob_xy;
  std::vector<bool> blob_lit;
  std::vector<int> true_blob;  // per dot, the blob showing it (-1: not seen)
};

// A cols x rows grid displayed at monitor pixels (400 + 24 c, 300 + 24 r), seen on the plane
// through `screen` with 0.02 mm of blob noise, shuffled, one dot missing and one speck added.
Scene MakeScene(const Screen& screen, int cols, int rows, bool mirrored, uint64_t seed) {
  Scene s;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 2e-5);
  const std::vector<int> fiducials = session::FiducialDots(cols, rows);
  s.grid.pixel_pitch_m = kPitch;
  s.grid.spacing_m = 24 * kPitch;
  s.grid.fiducial.assign(cols * rows, false);
  for (int q : fiducials) s.grid.fiducial[q] = true;
  const Eigen::Vector2d down = mirrored ? Eigen::Vector2d(-screen.down) : screen.down;
  std::vector<std::pair<Eigen::Vector2d, int>> seen;  // position, dot
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const Eigen::Vector2d px(400 + 24 * c + 0.5, 300 + 24 * r + 0.5);
      s.grid.monitor_px.push_back(px);
      const int q = r * cols + c;
      if (q == cols + 1) continue;  // a dot the camera did not see
      const Eigen::Vector2d xy = screen.corner + kPitch * (px.x() * screen.right + px.y() * down);
      seen.push_back({xy + Eigen::Vector2d(noise(rng), noise(rng)), q});
    }
  }
  seen.push_back({screen.corner + kPitch * (450 * screen.right + 250 * down), -1});  // a speck off the grid
  std::shuffle(seen.begin(), seen.end(), rng);
  s.true_blob.assign(cols * rows, -1);
  for (size_t b = 0; b < seen.size(); ++b) {
    s.blob_xy.push_back(seen[b].first);
    s.blob_lit.push_back(seen[b].second >= 0 && s.grid.fiducial[seen[b].second]);
    if (seen[b].second >= 0) s.true_blob[seen[b].second] = static_cast<int>(b);
  }
  return s;
}

Scene Turned(const Scene& scene, double degrees) {
  Scene turned = scene;
  const Eigen::Matrix2d r = Eigen::Rotation2Dd(degrees * M_PI / 180).toRotationMatrix();
  for (Eigen::Vector2d& b : turned.blob_xy) b = r * b;
  return turned;
}

TEST(DotIdentification, EveryOrientationOfAPhysicalScreenIsIdentified) {
  for (const Screen& screen : kScreens) {
    for (auto [cols, rows] : {std::pair{6, 6}, std::pair{9, 7}}) {
      const Scene scene = MakeScene(screen, cols, rows, false, 7);
      const DotIdentification id = IdentifyDots(scene.blob_xy, scene.blob_lit, scene.grid, std::nullopt, "fiducials/e0");
      EXPECT_EQ(id.chosen.blob_of_dot, scene.true_blob) << screen.orientation_deg << " " << cols << "x" << rows;
      EXPECT_FALSE(id.chosen.mirrored);
      EXPECT_NEAR(std::remainder(id.chosen.orientation_deg - screen.orientation_deg, 360.0), 0.0, 0.05);
      EXPECT_GT(id.chosen.fiducial_agreement, 0.99);
      EXPECT_LT(id.runner_up_agreement, 0.8);  // the other ways the grid could lie disagree
      EXPECT_EQ(id.identified_by, "fiducials");
      // A screen turned by a few degrees more is identified as well, and its turn measured.
      const DotIdentification turned =
          IdentifyDots(Turned(scene, 4.0).blob_xy, scene.blob_lit, scene.grid, screen.orientation_deg, "fiducials/e0");
      EXPECT_EQ(turned.chosen.blob_of_dot, scene.true_blob);
      EXPECT_NEAR(std::remainder(turned.chosen.orientation_deg - screen.orientation_deg - 4.0, 360.0), 0.0, 0.05);
    }
  }
}

TEST(DotIdentification, AMirroredScreenIsRefused) {
  for (const Screen& screen : kScreens) {
    const Scene scene = MakeScene(screen, 6, 6, /*mirrored=*/true, 11);
    try {
      IdentifyDots(scene.blob_xy, scene.blob_lit, scene.grid, std::nullopt, "SESSION/images/fiducials/e0.png");
      ADD_FAILURE() << "a mirrored screen at " << screen.orientation_deg << " degrees was accepted";
    } catch (const common::Error& e) {
      EXPECT_EQ(e.kind(), common::ErrorKind::kFormat);
      EXPECT_NE(std::string(e.what()).find("fiducials/e0.png"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("mirrored"), std::string::npos) << e.what();
    }
  }
}

TEST(DotIdentification, ContradictionsAndMissingEvidenceAreRefused) {
  const Scene scene = MakeScene(kScreens[1], 6, 6, false, 13);
  const auto expect_error = [&](const std::vector<bool>& lit, const DisplayedGrid& grid, std::optional<double> declared,
                                const std::string& words) {
    try {
      IdentifyDots(scene.blob_xy, lit, grid, declared, "the-source");
      ADD_FAILURE() << "accepted; expected an error saying '" << words << "'";
    } catch (const common::Error& e) {
      EXPECT_NE(std::string(e.what()).find("the-source"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
  };
  // The lab noted the screen a half turn from how the fiducials show it.
  expect_error(scene.blob_lit, scene.grid, 270.0, "rig.monitor.orientation_deg says");
  // Fiducial dots that are not the ones the display showed.
  std::vector<bool> wrong(scene.blob_lit.size());
  std::mt19937_64 rng(5);
  for (size_t b = 0; b < wrong.size(); ++b) wrong[b] = rng() & 1;
  expect_error(wrong, scene.grid, std::nullopt, "match no way the grid can lie");
  // No fiducial capture and nothing declared: the grid's half-turn symmetry leaves it open.
  DisplayedGrid bare = scene.grid;
  bare.fiducial.clear();
  expect_error({}, bare, std::nullopt, "cannot be told");
  // ... but a declared orientation decides it, and says so.
  const DotIdentification declared = IdentifyDots(scene.blob_xy, {}, bare, 90.0, "the-source");
  EXPECT_EQ(declared.chosen.blob_of_dot, scene.true_blob);
  EXPECT_EQ(declared.identified_by, "declared orientation");
}

// The fiducial set breaks every symmetry of the grid by a wide margin, for every grid size a
// capture plan can ask for that has one.
TEST(DotIdentification, FiducialDotsAreFarFromEverySymmetricImage) {
  for (int cols = 1; cols <= 40; ++cols) {
    for (int rows = 1; rows <= 40; rows += (rows < 8 ? 1 : 7)) {
      const int n = cols * rows;
      if (n < 9) continue;
      const std::vector<int> dots = session::FiducialDots(cols, rows);
      std::vector<bool> lit(n, false);
      for (int q : dots) lit[q] = true;
      EXPECT_TRUE(std::is_sorted(dots.begin(), dots.end()));
      EXPECT_GT(dots.size(), n / 5u) << cols << "x" << rows;
      EXPECT_LT(dots.size(), n - n / 5u) << cols << "x" << rows;
      const std::vector<std::vector<int>> symmetries = session::GridSymmetries(cols, rows);
      EXPECT_EQ(symmetries.size(), cols == rows ? 8u : 4u);
      std::vector<int> identity(n);
      std::iota(identity.begin(), identity.end(), 0);
      EXPECT_EQ(symmetries.front(), identity);
      for (size_t s = 1; s < symmetries.size(); ++s) {
        // Each is a permutation of the dots.
        EXPECT_EQ(std::set<int>(symmetries[s].begin(), symmetries[s].end()).size(), static_cast<size_t>(n));
        // 1-wide grids have symmetries that move nothing (a mirror across the line).
        if (symmetries[s] == identity) continue;
        EXPECT_GE(session::SymmetryDistance(lit, symmetries[s]), n / 4) << cols << "x" << rows << " symmetry " << s;
      }
    }
  }
}

}  // namespace
}  // namespace svbtdf::calib
