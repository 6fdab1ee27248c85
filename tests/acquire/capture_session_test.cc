// The capture loop of `svbtdf acquire` on the simulated rig: a full acquisition stores the
// simulator's very images; camera faults are retried with back-off and then stop cleanly with a
// resumable session; a full disk, a changed plan and an interrupt are clean, named errors; an
// unattended run can skip the captures that need an operator.
#include <gtest/gtest.h>

#include <filesystem>
#include <memory>
#include <sstream>

#include "svbtdf/acquire/capture_session.h"
#include "svbtdf/acquire/sim_hardware.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/interrupt.h"
#include "svbtdf/session/session.h"
#include "svbtdf/simulate/capture_render.h"
#include "svbtdf/acquire/simulated_session.h"
#include "temp_folder.h"

namespace svbtdf::acquire {
namespace {
namespace fs = std::filesystem;

class AcquireOnSimulatedRig : public ::testing::Test {
 protected:
  // The rig is built directly; `svbtdf simulate`'s session (3 s) only for the tests that compare
  // against it (ctest runs every test in a process of its own).
  static void SetUpTestSuite() {
    folder_ = std::make_unique<svbtdf::testing::TempFolder>("acquire");
    root_ = folder_->path();
    setup_ = simulate::MakeSimulatedSetup(simulate::MakePreset("tiny"), 1, 0);
    plan_ = new CapturePlan(MakePlanPreset("tiny"));
  }
  static void TearDownTestSuite() {
    folder_.reset();
    setup_.reset();
    delete plan_;
  }
  void SetUp() override {
    world_ = std::make_shared<SimWorld>();
    display_ = std::make_unique<SimDisplay>(world_, SimDisplayInfo(*setup_));
    camera_ = std::make_unique<SimCamera>(world_, setup_, "sim:test");
    op_ = std::make_unique<SimOperator>(world_);
    options_.progress = false;
    options_.sleep = [this](double seconds) { slept_.push_back(seconds); };
    common::SetInterruptRequested(false);
  }
  void TearDown() override { common::SetInterruptRequested(false); }

  AcquireResult Run(Camera& camera, const fs::path& out) {
    return Acquire(*plan_, camera, *display_, *op_, out, options_);
  }
  // Simulates tiny once per process and checks that the rig rebuilt from its folder (what
  // `--camera sim:DIR` uses) is the one the tests use.
  static fs::path SimulatedSession() {
    if (!fs::exists(root_ / "sim" / "session" / "journal.jsonl")) {
      simulate::SimulationOptions options;
      options.progress = false;
      acquire::SimulateSession(root_ / "sim", options);
      const std::shared_ptr<const simulate::SimulatedSetup> loaded = LoadSimulation(root_ / "sim");
      EXPECT_EQ(loaded->plan.dot_exposures_s, setup_->plan.dot_exposures_s);
    }
    return root_ / "sim" / "session";
  }
  void ExpectEqualToTheSimulator(const fs::path& out) {
    const session::Session acquired = session::Session::Open(out), simulated = session::Session::Open(SimulatedSession());
    EXPECT_TRUE(acquired.Verify().complete()) << acquired.Verify().Summary();
    ASSERT_EQ(acquired.planned_keys(), simulated.planned_keys());
    for (const std::string& key : simulated.planned_keys()) {
      EXPECT_EQ(acquired.Entry(key).crc32, simulated.Entry(key).crc32) << key;
      EXPECT_DOUBLE_EQ(acquired.Entry(key).exposure_s, simulated.Entry(key).exposure_s) << key;
    }
  }

  // The tiny plan's capture count and board views (they follow the simulator's preset).
  static int Planned() { return static_cast<int>(ExpandPlan(*plan_).size()); }
  static int BoardViews() { return plan_->board_views; }

  static inline fs::path root_;
  static inline std::unique_ptr<svbtdf::testing::TempFolder> folder_;
  static inline std::shared_ptr<const simulate::SimulatedSetup> setup_;
  static inline CapturePlan* plan_ = nullptr;
  std::shared_ptr<SimWorld> world_;
  std::unique_ptr<SimDisplay> display_;
  std::unique_ptr<SimCamera> camera_;
  std::unique_ptr<SimOperator> op_;
  AcquireOptions options_;
  std::vector<double> slept_;
};

TEST_F(AcquireOnSimulatedRig, TinyPlanStoresTheSimulatorsImages) {
  const fs::path out = root_ / "whole";
  const AcquireResult result = Run(*camera_, out);
  EXPECT_EQ(result.planned, Planned());
  EXPECT_EQ(result.captured, Planned());
  EXPECT_TRUE(result.complete());
  ExpectEqualToTheSimulator(out);
  // The manifest holds the nominal rig values calibration reads, as `svbtdf simulate` writes them.
  const nlohmann::json a = session::Session::Open(out).rig_json(), b = session::Session::Open(SimulatedSession()).rig_json();
  for (const char* key : {"/camera/width", "/camera/height", "/camera/bit_depth", "/camera/channels",
                          "/camera/response", "/board/spec", "/board/views", "/monitor/emission",
                          "/dots/radius_px", "/dots/positions_px", "/dots/fiducials", "/dots/cols",
                          "/monitor/orientation_deg", "/exposures_s"}) {
    EXPECT_EQ(a.at(nlohmann::json::json_pointer(key)), b.at(nlohmann::json::json_pointer(key))) << key;
  }
  for (const char* key : {"/monitor/pixel_pitch_m", "/monitor/distance_m", "/sample/width_m", "/sample/height_m"}) {
    EXPECT_NEAR(a.at(nlohmann::json::json_pointer(key)).get<double>(),
                b.at(nlohmann::json::json_pointer(key)).get<double>(), 1e-12) << key;
  }
  // Each pattern is shown once for all its brackets: 1 black, the boards + 1 holder share the black
  // pattern too (no re-show), all dots, fiducials, flat, 36 dots.
  EXPECT_EQ(world_->patterns_shown, 1 + 1 + 1 + 1 + 36);
  // A second run finds nothing to do and touches nothing.
  const AcquireResult again = Run(*camera_, out);
  EXPECT_EQ(again.already, Planned());
  EXPECT_EQ(again.captured, 0);
}

TEST_F(AcquireOnSimulatedRig, TransientCameraFailuresAreRetriedWithBackOff) {
  FaultInjectingCamera flaky(*camera_, {/*fail_at=*/10, /*fail_count=*/2, /*unplug=*/false});
  options_.retries = 3;
  options_.retry_backoff_s = 0.5;
  const AcquireResult result = Run(flaky, root_ / "flaky");
  EXPECT_TRUE(result.complete());
  EXPECT_EQ(result.retries, 2);
  EXPECT_EQ(flaky.failures(), 2);
  // Two back-offs, doubling, among the settle waits.
  EXPECT_NE(std::find(slept_.begin(), slept_.end(), 0.5), slept_.end());
  EXPECT_NE(std::find(slept_.begin(), slept_.end(), 1.0), slept_.end());
  ExpectEqualToTheSimulator(root_ / "flaky");
}

TEST_F(AcquireOnSimulatedRig, APulledCableStopsCleanlyAndTheSessionResumes) {
  const fs::path out = root_ / "unplugged";
  FaultInjectingCamera unplugged(*camera_, {/*fail_at=*/30, 1, /*unplug=*/true});
  options_.retries = 2;
  try {
    Run(unplugged, out);
    FAIL() << "a dead camera did not stop the acquisition";
  } catch (const common::Error& e) {
    EXPECT_EQ(e.kind(), common::ErrorKind::kHardware);
    EXPECT_NE(std::string(e.what()).find("cable pulled"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("3 times"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("resumable"), std::string::npos) << e.what();
  }
  EXPECT_EQ(unplugged.failures(), 3);
  const session::Session stopped = session::Session::Open(out);
  EXPECT_EQ(stopped.entries().size(), 29u);
  EXPECT_TRUE(stopped.Verify().corrupt.empty());
  // Cable back in: the same command captures only the rest.
  const AcquireResult resumed = Run(*camera_, out);
  EXPECT_EQ(resumed.already, 29);
  EXPECT_EQ(resumed.captured, Planned() - 29);
  EXPECT_TRUE(session::Session::Open(out).Verify().complete());
}

// Images are written on a thread of their own while the next is captured (BackgroundWriter): a
// write that fails must still stop the run with its own error, naming the file, with every image
// before it journalled and nothing after it.
TEST_F(AcquireOnSimulatedRig, AFailedWriteStopsTheRunWithItsErrorAndTheSessionResumes) {
  const fs::path out = root_ / "unwritable";
  const std::vector<PlannedCapture> captures = ExpandPlan(*plan_);
  constexpr int kBlocked = 20;
  // A folder where the image's file should go (made once the session exists): its rename fails
  // as on a broken disk.
  const fs::path blocked = out / session::Session::FileForKey(captures.at(kBlocked).key);
  options_.before_capture = [&](const PlannedCapture& capture) {
    if (capture.key == captures[kBlocked].key) fs::create_directories(blocked / "in-the-way");
  };
  try {
    Run(*camera_, out);
    FAIL() << "the failed write was not reported";
  } catch (const common::Error& e) {
    EXPECT_EQ(e.kind(), common::ErrorKind::kIo) << e.what();
    EXPECT_NE(std::string(e.what()).find(session::Session::FileForKey(captures.at(kBlocked).key)), std::string::npos)
        << e.what();
  }
  const session::Session stopped = session::Session::Open(out);
  ASSERT_EQ(stopped.entries().size(), size_t{kBlocked});
  for (int n = 0; n < kBlocked; ++n) EXPECT_EQ(stopped.entries()[n].key, captures[n].key);
  EXPECT_TRUE(stopped.Verify().corrupt.empty());
  fs::remove_all(blocked);
  options_.before_capture = nullptr;
  SimCamera fresh(world_, setup_, "sim:test");  // a new process, as after the interrupt below
  const AcquireResult resumed = Run(fresh, out);
  EXPECT_EQ(resumed.already, kBlocked);
  EXPECT_EQ(resumed.captured, Planned() - kBlocked);
  ExpectEqualToTheSimulator(out);
}

TEST_F(AcquireOnSimulatedRig, NotEnoughFreeSpaceIsRefusedBeforeAnythingIsWritten) {
  const fs::path out = root_ / "full-disk";
  fs::path asked;
  options_.free_space = [&](const fs::path& folder) {
    asked = folder;
    return uint64_t{5'000'000};  // 5 MB; ~90 images of 240x200 RGB16 need about 30 MB
  };
  try {
    Run(*camera_, out);
    FAIL() << "acquired without the space for it";
  } catch (const common::Error& e) {
    EXPECT_EQ(e.kind(), common::ErrorKind::kIo);
    EXPECT_NE(std::string(e.what()).find(out.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("5.0 MB free"), std::string::npos) << e.what();
  }
  EXPECT_EQ(asked, out);
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(world_->patterns_shown, 0);
  options_.free_space = [](const fs::path&) { return uint64_t{200'000'000}; };
  EXPECT_TRUE(Run(*camera_, out).complete());

  // Issue 15: the estimate counted every image at the window's size (27.3 MB for a 49.5 MB
  // session). Board views are whole-sensor frames; before any capture every image counts as
  // uncompressed, after some as the largest captured of its size class plus a margin.
  const session::Session session = session::Session::Open(out);
  const std::vector<PlannedCapture> captures = ExpandPlan(*plan_);
  uint64_t actual = 0;
  for (const session::SessionEntry& entry : session.entries()) actual += entry.bytes;
  const CameraInfo info = camera_->Info();
  ASSERT_FALSE(info.window.whole_sensor());
  const uint64_t fresh = EstimatedBytes(captures, *plan_, info);
  const uint64_t resumed = EstimatedBytes(captures, *plan_, info, &session);
  const uint64_t board_view = static_cast<uint64_t>(info.window.sensor_width) * info.window.sensor_height * 3 * 2;
  EXPECT_GE(fresh, board_view * plan_->board_views) << "board views count at the sensor's size";
  EXPECT_GE(fresh, actual);
  EXPECT_GE(resumed, actual);
  EXPECT_LE(resumed, actual * 3 / 2) << "from what was captured, within 50% of the real size";
  std::printf("session %.1f MB; estimated %.1f MB before capturing, %.1f MB from its images\n", actual / 1e6,
              fresh / 1e6, resumed / 1e6);
}

TEST_F(AcquireOnSimulatedRig, ADifferentPlanIsRefusedOnResume) {
  const fs::path out = root_ / "changed";
  FaultInjectingCamera unplugged(*camera_, {20, 1, true});
  options_.retries = 0;
  EXPECT_THROW(Run(unplugged, out), common::Error);
  const size_t stored = session::Session::Open(out).entries().size();
  CapturePlan longer = *plan_;
  longer.exposures_s[1] *= 2.0;  // same keys, another exposure: still another plan
  try {
    Acquire(longer, *camera_, *display_, *op_, out, options_);
    FAIL() << "resumed with another plan";
  } catch (const common::Error& e) {
    EXPECT_EQ(e.kind(), common::ErrorKind::kInvalidInput);
    EXPECT_NE(std::string(e.what()).find("different capture plan"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(out.string()), std::string::npos) << e.what();
  }
  EXPECT_EQ(session::Session::Open(out).entries().size(), stored);
  // A session another program wrote (`svbtdf simulate`: no acquisition plan) is not resumed
  // either, even with the same keys.
  session::Session::Create(root_ / "foreign", {{"simulated", true}}, PlanKeys(ExpandPlan(*plan_)));
  try {
    Run(*camera_, root_ / "foreign");
    FAIL() << "resumed a session acquire did not write";
  } catch (const common::Error& e) {
    EXPECT_NE(std::string(e.what()).find("did not write"), std::string::npos) << e.what();
  }
}

// An interrupt requested mid-capture stops between two captures with a resumable session.
class InterruptingCamera : public Camera {
 public:
  InterruptingCamera(Camera& inner, int after) : inner_(inner), after_(after) {}
  CameraInfo Info() const override { return inner_.Info(); }
  void SetExposure(const ExposureSettings& s) override { inner_.SetExposure(s); }
  Frame Capture() override {
    if (++calls_ == after_) common::SetInterruptRequested(true);
    return inner_.Capture();
  }

 private:
  Camera& inner_;
  int after_;
  int calls_ = 0;
};

TEST_F(AcquireOnSimulatedRig, AnInterruptStopsCleanlyAndTheSessionResumesToTheSameImages) {
  const fs::path out = root_ / "interrupted";
  InterruptingCamera interrupting(*camera_, 40);
  try {
    Run(interrupting, out);
    FAIL() << "the interrupt was ignored";
  } catch (const common::Error& e) {
    EXPECT_EQ(e.kind(), common::ErrorKind::kInterrupted);
    EXPECT_NE(std::string(e.what()).find("resumable"), std::string::npos) << e.what();
  }
  EXPECT_EQ(session::Session::Open(out).entries().size(), 40u);  // the capture in flight is kept
  common::SetInterruptRequested(false);
  // A new camera (a new process): dark frames and dots are numbered as the simulator's were, as
  // the resumed part holds no dark frame.
  SimCamera fresh(world_, setup_, "sim:test");
  EXPECT_EQ(Run(fresh, out).captured, Planned() - 40);
  ExpectEqualToTheSimulator(out);
}

TEST_F(AcquireOnSimulatedRig, UnattendedSkipTakesOnlyWhatNeedsNobody) {
  UnattendedOperator skip(UnattendedPolicy::kSkip);
  const AcquireResult result = Acquire(*plan_, *camera_, *display_, skip, root_ / "skip", options_);
  const int needs_operator = BoardViews() + 1 + 3;  // board views, sample plane, all dots, fiducials, flat white
  EXPECT_EQ(result.skipped, needs_operator);
  EXPECT_EQ(result.captured, Planned() - needs_operator);
  EXPECT_FALSE(result.complete());
  const session::SessionVerification report = session::Session::Open(root_ / "skip").Verify();
  EXPECT_EQ(report.missing.size(), static_cast<size_t>(needs_operator));
  EXPECT_TRUE(report.corrupt.empty());
}

TEST_F(AcquireOnSimulatedRig, SimDisplayRastersTheDotItShows) {
  Pattern dot;
  dot.kind = Pattern::Kind::kDot;
  dot.x_px = 100;
  dot.y_px = 50;
  dot.dot_radius_px = 4;
  display_->Show(dot);
  const DisplayInfo info = display_->Info();
  const std::vector<uint8_t> codes = display_->Raster();
  ASSERT_EQ(codes.size(), static_cast<size_t>(info.width_px) * info.height_px);
  EXPECT_EQ(codes[50 * info.width_px + 100], 255);
  EXPECT_EQ(codes[50 * info.width_px + 110], 0);
  // The simulated camera refuses a pattern it cannot render (a chessboard on the monitor), naming
  // itself.
  Pattern board;
  board.kind = Pattern::Kind::kChessboard;
  display_->Show(board);
  camera_->SetExposure({0.01, 1.0});
  try {
    camera_->Capture();
    FAIL();
  } catch (const common::Error& e) {
    EXPECT_NE(std::string(e.what()).find("sim:test"), std::string::npos) << e.what();
  }
}

// A plan of one's own (a 3 x 2 grid, another radius, half intensity) on the simulated rig: the
// dots are rendered by the simulator wherever they are, so the dot image that sits straight
// behind the sample centre is bright and a half-intensity dot is half as bright as a full one.
TEST_F(AcquireOnSimulatedRig, AnyPlansDotsAreRenderedByTheSimulator) {
  CapturePlan own;
  own.name = "own";
  own.dot_cols = 3;
  own.dot_rows = 2;
  const simulate::Dot& centre = setup_->rig->dots()[14];  // near the middle of the tiny 6 x 6 grid
  for (int row = 0; row < 2; ++row) {
    for (int col = 0; col < 3; ++col) own.dots_px.emplace_back(centre.monitor_x + 7.5 * col, centre.monitor_y + 5.0 * row);
  }
  own.dot_radius_px = 3.0;
  own.exposures_s = {plan_->exposures_s[0]};
  own.dark_frames = 1;
  own.settle_s = 0;
  const AcquireResult full = Acquire(own, *camera_, *display_, *op_, root_ / "own", options_);
  EXPECT_TRUE(full.complete());
  EXPECT_EQ(full.captured, 1 + 6);
  own.dot_intensity = 0.5;
  Acquire(own, *camera_, *display_, *op_, root_ / "own-half", options_);
  const auto sum = [](const common::CameraImage& image) {
    double total = 0;
    for (uint16_t v : image.pixels) total += v;
    return total;
  };
  const session::Session a = session::Session::Open(root_ / "own"), b = session::Session::Open(root_ / "own-half");
  const double dark = sum(a.ReadImage("dark/e0/r0"));
  const double bright = sum(a.ReadImage("dot/q0000/e0/r0")) - dark;
  const double half = sum(b.ReadImage("dot/q0000/e0/r0")) - dark;
  EXPECT_GT(bright, 1.0 * a.ReadImage("dark/e0/r0").pixels.size());  // > 1 DN per pixel on average
  EXPECT_NEAR(half / bright, 0.5, 0.02);
}

TEST_F(AcquireOnSimulatedRig, ACameraOfAnotherFrameSizeCannotResumeTheSession) {
  const fs::path out = root_ / "other-camera";
  FaultInjectingCamera unplugged(*camera_, {5, 1, true});
  options_.retries = 0;
  EXPECT_THROW(Run(unplugged, out), common::Error);
  // A camera that delivers half-size frames.
  class Cropping : public Camera {
   public:
    explicit Cropping(Camera& inner) : inner_(inner) {}
    CameraInfo Info() const override { return inner_.Info(); }
    void SetExposure(const ExposureSettings& s) override { inner_.SetExposure(s); }
    Frame Capture() override {
      Frame f = inner_.Capture();
      f.height /= 2;
      f.pixels.resize(static_cast<size_t>(f.width) * f.height * f.channels);
      return f;
    }

   private:
    Camera& inner_;
  } cropping(*camera_);
  try {
    Run(cropping, out);
    FAIL() << "mixed frame sizes in one session";
  } catch (const common::Error& e) {
    // The resumed run starts with the Zhang views, whole-sensor frames of the 1280 x 1024 sensor.
    EXPECT_NE(std::string(e.what()).find("1280x512x3 frames but the camera's sensor is 1280x1024x3"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(session::Session::Open(out).entries().size(), 4u);
}

// A display whose pipeline puts what it is given on screen `frames` refreshes after Show returns
// (as a TV's processing or a compositor's extra buffer does), and a camera that notes when it is
// triggered, on one clock that only waiting advances: the loop must never trigger before the
// pattern's presentation plus the settle time, and must journal that presentation.
TEST_F(AcquireOnSimulatedRig, TheCameraWaitsForTheDelayedPresentationPlusTheSettleTime) {
  struct Clock {
    double now = 5000.0;
  } clock;
  constexpr int kFrames = 4;
  constexpr double kRefresh = 1.0 / 60.0;
  class DelayedDisplay : public Display {
   public:
    DelayedDisplay(Display& inner, Clock& clock) : inner_(inner), clock_(clock) {}
    DisplayInfo Info() const override { return inner_.Info(); }
    Presentation Show(const Pattern& pattern) override {
      inner_.Show(pattern);
      returned_s = clock_.now;
      presented_s = clock_.now + kFrames * kRefresh;
      return {presented_s, 0, true};
    }
    double returned_s = 0.0, presented_s = 0.0;

   private:
    Display& inner_;
    Clock& clock_;
  } display(*display_, clock);
  class TimedCamera : public Camera {
   public:
    TimedCamera(Camera& inner, Clock& clock, const DelayedDisplay& display)
        : inner_(inner), clock_(clock), display_(display) {}
    CameraInfo Info() const override { return inner_.Info(); }
    void SetExposure(const ExposureSettings& settings) override { inner_.SetExposure(settings); }
    Frame Capture() override {
      after_presentation_s.push_back(clock_.now - display_.presented_s);
      after_show_returned_s.push_back(clock_.now - display_.returned_s);
      presented_s.push_back(display_.presented_s);
      clock_.now += 0.001;  // the exposure and read-out
      return inner_.Capture();
    }
    std::vector<double> after_presentation_s, after_show_returned_s, presented_s;

   private:
    Camera& inner_;
    Clock& clock_;
    const DelayedDisplay& display_;
  } camera(*camera_, clock, display);
  options_.now = [&clock] { return clock.now; };
  options_.sleep = [&clock](double seconds) { clock.now += seconds; };
  const fs::path out = root_ / "delayed";
  const AcquireResult result = Acquire(*plan_, camera, display, *op_, out, options_);
  ASSERT_TRUE(result.complete());
  ASSERT_EQ(camera.after_presentation_s.size(), static_cast<size_t>(Planned()));
  const double settle = plan_->settle_s;
  for (size_t k = 0; k < camera.after_presentation_s.size(); ++k) {
    EXPECT_GE(camera.after_presentation_s[k], settle - 1e-9) << "capture " << k;
    // Waiting only the settle time after Show returned, as the loop did, would trigger
    // kFrames refreshes early.
    EXPECT_GE(camera.after_show_returned_s[k], kFrames * kRefresh + settle - 1e-9) << "capture " << k;
  }
  // The journal records each capture's presentation, the one the camera waited for.
  const session::Session session = session::Session::Open(out);
  for (size_t k = 0; k < session.entries().size(); ++k) {
    EXPECT_DOUBLE_EQ(session.entries()[k].presented_s, camera.presented_s[k]) << session.entries()[k].key;
  }
  ExpectEqualToTheSimulator(out);  // waiting changes no image
}

TEST(ConsoleOperator, EnterCapturesSSkipsAndEndOfInputSkips) {
  std::istringstream in("\ns\n");
  std::ostringstream out;
  ConsoleOperator op(in, out);
  EXPECT_TRUE(op.Prepare(Scene::kBoardView, 3, "hold the board, pose 3"));
  EXPECT_FALSE(op.Prepare(Scene::kNoSample, 0, "remove the sample"));
  EXPECT_FALSE(op.Prepare(Scene::kSample, 0, "put the sample back"));
  EXPECT_NE(out.str().find("hold the board, pose 3"), std::string::npos);
  EXPECT_NE(out.str().find("put the sample back"), std::string::npos);
}

}  // namespace
}  // namespace svbtdf::acquire
