// Sessions of a physical screen lying in each of the four ways a lab may put it down. The dots'
// expected positions are written here from first principles (the screen's top-left corner and its
// right and down vectors in the sample frame, as seen from the sample), not taken from the
// simulator's own frame, so that the simulator and the calibration cannot share a wrong
// convention unnoticed (they once did: both assumed a mirror image of a screen). A mirrored
// display and a lab note that contradicts the fiducials are refused.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <fstream>

#include <nlohmann/json.hpp>

#include "svbtdf/calib/calibrate_session.h"
#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/progress.h"
#include "svbtdf/session/session.h"
#include "svbtdf/process/process_session.h"
#include "svbtdf/fit/slice_store.h"
#include "svbtdf/acquire/simulated_session.h"
#include "svbtdf/simulate/truth_io.h"
#include "measured_btdf_error.h"
#include "temp_folder.h"

namespace svbtdf::calib {
namespace {
namespace fs = std::filesystem;

// Seen from the camera's side (+z toward the viewer, +x right, +y up): a screen's pixel x axis
// runs `right` and its pixel y axis `down`; right x down points into the screen (-z).
struct Orientation {
  double degrees;
  model::Vec3 right, down;
};

void PrintTo(const Orientation& o, std::ostream* out) { *out << o.degrees << " degrees"; }

const Orientation kOrientations[] = {
    {0, {1, 0, 0}, {0, -1, 0}},
    {90, {0, 1, 0}, {1, 0, 0}},
    {180, {-1, 0, 0}, {0, 1, 0}},
    {270, {0, -1, 0}, {-1, 0, 0}},
};

// The sessions are simulated once per program and shared by every test in it (a direct run of
// calib_tests simulates o0 and o90 once); the folder goes when the program ends.
fs::path Root() {
  static const svbtdf::testing::TempFolder root("physical-monitor");
  return root.path();
}

fs::path Simulate(const std::string& name, double orientation_deg, bool mirrored) {
  const fs::path out = Root() / name;
  if (fs::exists(out / "session" / "session.json")) return out;
  simulate::SimulationOptions options;
  options.preset = "tiny";
  options.progress = false;
  options.monitor_orientation_deg = orientation_deg;
  options.monitor_tilt_deg = 0.0;
  options.mirror_monitor = mirrored;
  acquire::SimulateSession(out, options);
  return out;
}

CalibrateSessionOptions Quiet() {
  CalibrateSessionOptions options;
  options.progress = false;
  return options;
}

class PhysicalMonitorTest : public ::testing::TestWithParam<Orientation> {
 protected:
  static void SetUpTestSuite() { common::ProgressBar::SetEnabled(false); }
};

TEST_P(PhysicalMonitorTest, DotsLandWhereAScreenLyingSoShowsThem) {
  const Orientation& o = GetParam();
  const fs::path out = Simulate("o" + std::to_string(static_cast<int>(o.degrees)), o.degrees, false);
  const session::Session session = session::Session::Open(out / "session");
  const simulate::RigTruth truth = simulate::ReadRigTruth(out / "truth" / "rig.json");
  // The screen's active area: centre, size and distance are the rig's; its axes are the test's.
  const simulate::MonitorConfig& m = truth.monitor;
  const model::Vec3 corner = model::Vec3(m.centre.x(), m.centre.y(), -m.distance) - 0.5 * m.width * o.right - 0.5 * m.height * o.down;
  std::vector<model::Vec3> expected;
  for (const auto& [i, j] : session.rig().dots.positions_px) {
    expected.push_back(corner + m.pixel_pitch * ((i + 0.5) * o.right + (j + 0.5) * o.down));
  }
  ASSERT_EQ(expected.size(), truth.dots.size());
  // The simulator shows a physical screen ...
  for (size_t q = 0; q < expected.size(); ++q) {
    EXPECT_LT((truth.dots[q].position - expected[q]).norm(), 1e-9) << "dot " << q;
  }
  // ... and calibration finds every dot where the screen put it.
  const SessionCalibration c = CalibrateSession(session, Quiet());
  double worst_mm = 0;
  for (size_t q = 0; q < expected.size(); ++q) {
    worst_mm = std::max(worst_mm, 1000.0 * (c.monitor.dots[q].position - expected[q]).norm());
  }
  std::printf("orientation %3.0f: measured %.2f degrees, worst dot %.3f mm, fiducials agree %.3f (next best %.3f)\n",
              o.degrees, c.monitor.orientation_deg, worst_mm, c.monitor.fiducial_agreement, c.monitor.fiducial_runner_up);
  EXPECT_LT(worst_mm, 0.2);
  EXPECT_NEAR(std::remainder(c.monitor.orientation_deg - o.degrees, 360.0), 0.0, 0.5);
  EXPECT_GT(c.monitor.normal.z(), 0.999);  // toward the sample
  EXPECT_NE(c.monitor.identified_by.find("fiducials/e0"), std::string::npos);
  EXPECT_GT(c.monitor.fiducial_agreement, 0.95);

  // With the right dots, processing measures the true BTDF (a mislabelled grid puts every sample
  // at another dot's direction: errors of tens of percent).
  process::ProcessOptions options;
  options.progress = false;
  process::ProcessSession(session, c, out / "processed", options);
  const fit::SliceStore store = fit::SliceStore::Open(out / "processed");
  size_t count = 0;
  const double median = svbtdf::testing::MedianBtdfError(store, simulate::ReadMaterialTruth(out / "truth"), expected,
                                                         truth.pose.Centre(), &count);
  std::printf("orientation %3.0f: median |R/R_true - 1| %.4f over %zu samples\n", o.degrees, median, count);
  ASSERT_GT(count, 0u);
  EXPECT_LT(median, 0.03);
}

INSTANTIATE_TEST_SUITE_P(FourWaysDown, PhysicalMonitorTest, ::testing::ValuesIn(kOrientations),
                         [](const ::testing::TestParamInfo<Orientation>& info) {
                           return "Deg" + std::to_string(static_cast<int>(info.param.degrees));
                         });

void ExpectRefused(const fs::path& session, const std::string& file, const std::string& words) {
  try {
    CalibrateSession(session::Session::Open(session), Quiet());
    ADD_FAILURE() << session << " was calibrated; expected an error saying '" << words << "'";
  } catch (const common::Error& e) {
    EXPECT_EQ(e.kind(), common::ErrorKind::kFormat);
    EXPECT_NE(std::string(e.what()).find(file), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
  }
}

TEST(PhysicalMonitor, AMirroredDisplayIsRefusedNamingTheFiducialCapture) {
  common::ProgressBar::SetEnabled(false);
  const fs::path out = Simulate("mirrored", 0.0, /*mirrored=*/true);
  ExpectRefused(out / "session", "fiducials/e0.png", "mirrored");
}

// A copy NAME of the session in OUT whose manifest's rig `edit` changed (the images are the same).
fs::path CopyWithEditedRig(const fs::path& out, const std::string& name,
                           const std::function<void(nlohmann::json& rig)>& edit) {
  const fs::path copy = Root() / name;
  fs::remove_all(copy);
  fs::copy(out / "session", copy, fs::copy_options::recursive);
  nlohmann::json manifest = nlohmann::json::parse(common::ReadTextFile(copy / "session.json"));
  edit(manifest["rig"]);
  std::ofstream(copy / "session.json", std::ios::trunc) << manifest.dump(2);
  return copy;
}

TEST(PhysicalMonitor, ALabNoteThatContradictsTheFiducialsIsRefused) {
  common::ProgressBar::SetEnabled(false);
  const fs::path copy = CopyWithEditedRig(Simulate("o0", 0.0, false), "contradicted", [](nlohmann::json& rig) {
    rig["monitor"]["orientation_deg"] = 180.0;  // the lab noted the screen upside down
  });
  ExpectRefused(copy, "fiducials/e0.png", "rig.monitor.orientation_deg says 180");
}

// A misspelt emission profile would silently become isotropic and bias every dot's L_q: refused
// before any image is read, naming the manifest and the key.
TEST(PhysicalMonitor, AMisspeltEmissionProfileIsRefused) {
  common::ProgressBar::SetEnabled(false);
  const fs::path copy = CopyWithEditedRig(Simulate("o0", 0.0, false), "misspelt", [](nlohmann::json& rig) {
    rig["monitor"]["emission"] = "lambertain";
  });
  ExpectRefused(copy, "session.json", "rig.monitor.emission 'lambertain'");
}

// Dots displayed elsewhere than the session says (here each moved by up to 4 monitor pixels, 1 mm)
// fit no flat grid of the stated layout: refused, naming the all-dots image, not turned into
// wrong dot positions.
TEST(PhysicalMonitor, DotsFarOffAnyGridOfTheStatedLayoutAreRefused) {
  common::ProgressBar::SetEnabled(false);
  const fs::path copy = CopyWithEditedRig(Simulate("o90", 90.0, false), "moved", [](nlohmann::json& rig) {
    int k = 0;
    for (nlohmann::json& p : rig["dots"]["positions_px"]) {
      p[0] = p[0].get<int>() + (k % 3 - 1) * 4;
      p[1] = p[1].get<int>() + ((k / 3) % 3 - 1) * 4;
      ++k;
    }
  });
  ExpectRefused(copy, "all_dots/e0.png", "off");
}

}  // namespace
}  // namespace svbtdf::calib
