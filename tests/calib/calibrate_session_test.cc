// Calibrating simulated sessions against their ground truth (issue 4's acceptance), robustness
// of the dot matching to missing and extra blobs, and errors that name the file.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <vector>

#include <nlohmann/json.hpp>

#include "svbtdf/calib/calibrate_session.h"
#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/image_io.h"
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

class CalibrateSessionTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    common::ProgressBar::SetEnabled(false);
    folder_ = std::make_unique<svbtdf::testing::TempFolder>("calibrate-session");
    root_ = folder_->path();
    simulate::SimulationOptions options;
    options.preset = "tiny";
    options.progress = false;
    acquire::SimulateSession(root_ / "sim", options);
    truth_ = simulate::ReadRigTruth(root_ / "sim" / "truth" / "rig.json");
  }
  static void TearDownTestSuite() { folder_.reset(); }

  static CalibrateSessionOptions Quiet() {
    CalibrateSessionOptions options;
    options.progress = false;
    return options;
  }

  // The worst distance (mm) between calibrated and true dot positions.
  static double WorstDotErrorMm(const SessionCalibration& c) {
    double worst = 0;
    for (size_t q = 0; q < truth_.dots.size(); ++q) {
      worst = std::max(worst, 1000.0 * (c.monitor.dots[q].position - truth_.dots[q].position).norm());
    }
    return worst;
  }

  // A copy of the session whose image `key` is replaced by `edit(image)`. The files are copied
  // and only the edited image is journalled anew (re-encoding the whole-sensor board views would
  // take most of the test's time).
  static fs::path EditedCopy(const std::string& name, const std::string& key,
                             const std::function<void(common::CameraImage*)>& edit) {
    const fs::path copy = root_ / name;
    fs::remove_all(copy);
    const session::Session original = session::Session::Open(root_ / "sim" / "session");
    fs::copy(original.folder(), copy, fs::copy_options::recursive);
    const session::SessionEntry& entry = original.Entry(key);
    common::CameraImage image = original.ReadImage(key);
    edit(&image);
    std::ifstream journal_in(copy / "journal.jsonl");
    std::string kept, line;
    while (std::getline(journal_in, line)) {
      if (nlohmann::json::parse(line).value("key", "") != key) kept += line + "\n";
    }
    journal_in.close();
    std::ofstream(copy / "journal.jsonl", std::ios::trunc) << kept;
    fs::remove(copy / entry.file);
    session::Session edited = session::Session::Open(copy);
    EXPECT_FALSE(edited.Contains(key));
    edited.AddImage(key, image, entry.exposure_s, entry.gain);
    return copy;
  }

  static inline std::unique_ptr<svbtdf::testing::TempFolder> folder_;
  static inline fs::path root_;
  static inline simulate::RigTruth truth_;
};

// Issue 4's targets on the tiny rig: the paper's geometry (camera 1 m from the sample at 45
// degrees, f = 2200 px), the dot images a 240 x 200 window of a 1280 x 1024 sensor (a 32 degree
// lens), the Zhang views whole-sensor images of an 11 x 8 board of 25 mm squares. Focal lengths
// within 0.5%, principal point within 2 px, dots within 0.2 mm.
TEST_F(CalibrateSessionTest, RecoversTheRigWithinTheStatedTolerances) {
  const SessionCalibration c = CalibrateSession(session::Session::Open(root_ / "sim" / "session"), Quiet());
  const CameraModel& camera = c.camera.camera;
  const double centre_error_mm = 1000 * (c.sample_plane.CameraCentre() - truth_.pose.Centre()).norm();
  const double dot_error_mm = WorstDotErrorMm(c);
  std::printf("fx %.2f +- %.2f (true %.2f), fy %.2f (true %.2f), cx %.2f +- %.2f (true %.2f), cy %.2f +- %.2f (true %.2f)\n",
              camera.fx, c.camera.intrinsics_std[0], truth_.camera.fx, camera.fy, truth_.camera.fy, camera.cx,
              c.camera.intrinsics_std[2], truth_.camera.cx, camera.cy, c.camera.intrinsics_std[3], truth_.camera.cy);
  std::printf("camera centre %.2f mm off, monitor %.3f mm (its centre %.3f), worst dot %.3f mm off, dot residual RMS "
              "%.3f mm, orientation %.2f degrees (true %.2f)\n",
              centre_error_mm, 1000 * c.monitor.distance_m, 1000 * truth_.monitor.distance, dot_error_mm,
              c.monitor.residual_rms_mm, c.monitor.orientation_deg, truth_.monitor.orientation_deg);
  EXPECT_TRUE(c.camera.narrow_lens_because.empty()) << c.camera.narrow_lens_because;
  EXPECT_EQ(camera.width, truth_.camera.width);  // the window's intrinsics
  EXPECT_NEAR(camera.fx / truth_.camera.fx, 1.0, 0.005);
  EXPECT_NEAR(camera.fy / truth_.camera.fy, 1.0, 0.005);
  EXPECT_LT(std::abs(camera.cx - truth_.camera.cx), 2.0);
  EXPECT_LT(std::abs(camera.cy - truth_.camera.cy), 2.0);
  EXPECT_LT(centre_error_mm, 10.0);
  // d is where the monitor's plane crosses the sample's normal through its centre: the screen
  // is tilted, so not its centre's depth.
  const simulate::MonitorFrame screen = simulate::MonitorFrame::Of(truth_.monitor);
  EXPECT_NEAR(c.monitor.distance_m, -screen.normal.dot(screen.origin) / screen.normal.z(), 0.5e-3);
  EXPECT_LT(std::acos(std::min(1.0, c.monitor.normal.dot(screen.normal))), 0.2 * model::kPi / 180);  // the tilt, within 0.2 degrees
  EXPECT_LT(dot_error_mm, 0.2);
  EXPECT_EQ(c.monitor.dots.size(), truth_.dots.size());
  EXPECT_NEAR(c.monitor.orientation_deg, truth_.monitor.orientation_deg, 0.2);  // the preset's 91.5
}

// calibration.json is what `svbtdf process` and `svbtdf run` read back, and users may edit or
// bring one: it must read back as written, and damaged copies must be an Error naming the file,
// never a crash or another exception.
// Calibration is a function of the images alone: the same session calibrated twice, the second
// time at a longer path and with the heap laid out otherwise (as in a resumed `run`), gives the
// same bits. ATLAS's LAPACK, behind OpenCV's calibration, did not (the 10th digit of fx moved):
// cmake/ReferenceLinearAlgebra.cmake.
TEST_F(CalibrateSessionTest, CalibrationIsBitReproducibleWhateverThePathAndMemoryLayout) {
  const auto without_provenance = [](const SessionCalibration& c) {
    nlohmann::json json = ToJson(c);
    json.erase("provenance");  // names the session's folder
    return json.dump();
  };
  const std::string first = without_provenance(CalibrateSession(session::Session::Open(root_ / "sim" / "session"), Quiet()));
  const fs::path moved = root_ / "a-session-at-a-much-longer-path-than-the-first-one";
  fs::copy(root_ / "sim" / "session", moved, fs::copy_options::recursive);
  std::vector<std::vector<char>> ballast;  // odd-sized blocks held across the second calibration
  for (int k = 1; k < 200; ++k) ballast.emplace_back(static_cast<size_t>(k * 24 + 8));
  const std::string second = without_provenance(CalibrateSession(session::Session::Open(moved), Quiet()));
  EXPECT_TRUE(first == second) << "the calibrations differ";
}

TEST_F(CalibrateSessionTest, CalibrationFileRoundTripsAndDamageIsAClearError) {
  SessionCalibration c = CalibrateSession(session::Session::Open(root_ / "sim" / "session"), Quiet());
  c.camera.narrow_lens_because = "a test reason";  // the lens model must survive the trip too
  const fs::path path = root_ / "calibration.json";
  WriteSessionCalibration(path, c);
  const SessionCalibration back = ReadSessionCalibration(path);
  EXPECT_EQ(back.camera.camera.width, c.camera.camera.width);
  EXPECT_DOUBLE_EQ(back.camera.camera.fx, c.camera.camera.fx);
  EXPECT_DOUBLE_EQ(back.camera.camera.cy, c.camera.camera.cy);
  EXPECT_EQ(back.camera.camera.distortion, c.camera.camera.distortion);
  EXPECT_EQ(back.camera.narrow_lens_because, "a test reason");
  EXPECT_TRUE(back.sample_plane.rotation.isApprox(c.sample_plane.rotation, 1e-12));
  EXPECT_TRUE(back.sample_plane.translation.isApprox(c.sample_plane.translation, 1e-12));
  ASSERT_EQ(back.monitor.dots.size(), c.monitor.dots.size());
  for (size_t q = 0; q < c.monitor.dots.size(); ++q) {
    EXPECT_LT((back.monitor.dots[q].position - c.monitor.dots[q].position).norm(), 1e-12);
  }
  EXPECT_EQ(back.provenance, c.provenance);

  const std::string original = common::ReadTextFile(path);
  std::mt19937_64 rng(3);
  int refused = 0;
  for (int trial = 0; trial < 300; ++trial) {
    std::string damaged = original;
    const int mode = trial % 3;
    if (mode == 0) damaged.resize(rng() % damaged.size());
    if (mode == 1) damaged[rng() % damaged.size()] = static_cast<char>(rng() % 256);
    if (mode == 2) damaged.insert(rng() % damaged.size(), std::string(1 + rng() % 5, "{}[]\",:0e9-x\n"[rng() % 13]));
    const fs::path damaged_path = root_ / "damaged.json";
    std::ofstream(damaged_path, std::ios::trunc) << damaged;
    try {
      ReadSessionCalibration(damaged_path);
    } catch (const common::Error& e) {
      ++refused;
      EXPECT_NE(std::string(e.what()).find("damaged.json"), std::string::npos) << e.what();
    } catch (const std::exception& e) {
      FAIL() << "trial " << trial << ": " << e.what();
    }
  }
  EXPECT_GT(refused, 100);  // every truncation at least
}

TEST_F(CalibrateSessionTest, ProcessingWithTheCalibrationMeasuresTheTrueBtdf) {
  const session::Session session = session::Session::Open(root_ / "sim" / "session");
  const SessionCalibration c = CalibrateSession(session, Quiet());
  process::ProcessOptions options;
  options.progress = false;
  process::ProcessSession(session, c, root_ / "processed", options);
  const fit::SliceStore store = fit::SliceStore::Open(root_ / "processed");
  // Measured R against the truth at the true directions of each sample (5% of the peak and up).
  std::vector<model::Vec3> dots;
  for (const simulate::Dot& dot : truth_.dots) dots.push_back(dot.position);
  size_t count = 0;
  const double median = svbtdf::testing::MedianBtdfError(store, simulate::ReadMaterialTruth(root_ / "sim" / "truth"), dots,
                                                         truth_.pose.Centre(), &count);
  std::printf("median |R/R_true - 1| with the calibrated rig: %.4f over %zu samples\n", median, count);
  ASSERT_GT(count, 0u);
  EXPECT_LT(median, 0.03);
}

TEST_F(CalibrateSessionTest, MissingAndExtraDotsAreMatchedCorrectly) {
  const SessionCalibration reference = CalibrateSession(session::Session::Open(root_ / "sim" / "session"), Quiet());
  // Black out two dots and add a bright speck far from the grid.
  const fs::path edited = EditedCopy("edited", "all_dots/e0", [&](common::CameraImage* image) {
    for (int q : {7, 20}) {
      const Eigen::Vector2d& p = reference.monitor.dots[q].image_px;
      for (int y = static_cast<int>(p.y()) - 5; y <= static_cast<int>(p.y()) + 5; ++y) {
        for (int x = static_cast<int>(p.x()) - 5; x <= static_cast<int>(p.x()) + 5; ++x) {
          for (int c = 0; c < image->channels; ++c) image->pixels[(static_cast<size_t>(y) * image->width + x) * image->channels + c] = 0;
        }
      }
    }
    for (int y = 2; y < 5; ++y) {
      for (int x = 2; x < 5; ++x) {
        for (int c = 0; c < image->channels; ++c) image->pixels[(static_cast<size_t>(y) * image->width + x) * image->channels + c] = 4000;
      }
    }
  });
  const SessionCalibration c = CalibrateSession(session::Session::Open(edited), Quiet());
  EXPECT_LT(c.monitor.dots[7].residual_mm, 0.0);   // reported as not found
  EXPECT_LT(c.monitor.dots[20].residual_mm, 0.0);
  int found = 0;
  for (const DotPosition& dot : c.monitor.dots) found += dot.residual_mm >= 0;
  EXPECT_EQ(found, static_cast<int>(truth_.dots.size()) - 2);
  // Missing dots still get their place on the fitted grid, as close to the truth as the dots of
  // the intact session (RecoversTheRigWithinTheStatedTolerances).
  std::printf("with two dots missing and a speck: worst dot %.3f mm off\n", WorstDotErrorMm(c));
  EXPECT_LT(WorstDotErrorMm(c), 0.2);  // issue 4 target, as without the damage
}

TEST_F(CalibrateSessionTest, ABoardThatIsNotFoundIsAnErrorNamingTheImage) {
  const fs::path edited = EditedCopy("no_board", "sample_plane/v00", [](common::CameraImage* image) {
    std::fill(image->pixels.begin(), image->pixels.end(), 100);
  });
  try {
    CalibrateSession(session::Session::Open(edited), Quiet());
    FAIL() << "a blank sample-plane view was accepted";
  } catch (const common::Error& e) {
    EXPECT_NE(std::string(e.what()).find("sample_plane/v00.png"), std::string::npos) << e.what();
  }
  // Nothing in the session was written by the failed calibration.
  EXPECT_FALSE(fs::exists(edited / "calibration.json"));
}

}  // namespace
}  // namespace svbtdf::calib
