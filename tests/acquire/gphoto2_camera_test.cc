// libgphoto2 driver logic (shutter / ISO choice, JPEG selection, download and decode) against a
// fake session, plus a smoke test with a real tethered camera when one is connected.

#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "svbtdf/acquire/gphoto2_camera.h"
#include "expect_error.h"
#include "svbtdf/common/error.h"
#include "test_jpeg.h"

namespace svbtdf::acquire {
namespace {

class FakeGphoto2Session : public Gphoto2Session {
 public:
  struct State {
    std::map<std::string, std::vector<std::string>> widgets;
    std::map<std::string, std::string> values;
    std::vector<std::string> writes;
    std::vector<Gphoto2File> next_capture;
    int captures = 0;
    bool last_delete = false;
  };
  explicit FakeGphoto2Session(std::shared_ptr<State> state) : state_(std::move(state)) {}
  std::string Model() const override { return "Canon EOS 30D"; }
  std::string Port() const override { return "usb:001,004"; }
  bool HasWidget(const std::string& name) override { return state_->widgets.count(name) > 0; }
  std::vector<std::string> Choices(const std::string& name) override {
    const auto found = state_->widgets.find(name);
    return found == state_->widgets.end() ? std::vector<std::string>{} : found->second;
  }
  void SetWidget(const std::string& name, const std::string& value) override {
    state_->writes.push_back(name + "=" + value);
    state_->values[name] = value;
  }
  std::vector<Gphoto2File> CaptureAndDownload(bool delete_from_card) override {
    ++state_->captures;
    state_->last_delete = delete_from_card;
    return state_->next_capture;
  }

 private:
  std::shared_ptr<State> state_;
};

std::shared_ptr<FakeGphoto2Session::State> Canon30D() {
  auto state = std::make_shared<FakeGphoto2Session::State>();
  state->widgets["shutterspeed"] = {"bulb", "30", "15", "1\"3", "1", "0.5", "1/4", "1/250", "1/8000"};
  state->widgets["iso"] = {"Auto", "100", "200", "400", "800", "1600", "3200"};
  state->widgets["imageformat"] = {"RAW", "RAW + Large Fine JPEG", "Small Fine JPEG",
                                   "Large Normal JPEG", "Large Fine JPEG"};
  state->next_capture = {{"IMG_0001.CR2", "image/x-canon-cr2", {1, 2, 3}},
                         {"IMG_0001.JPG", "image/jpeg", testing::EncodeTestJpeg(24, 16)}};
  return state;
}

using svbtdf::testing::ExpectError;

TEST(Gphoto2ParseTest, ShutterSpeedsAndIsos) {
  EXPECT_DOUBLE_EQ(*ParseShutterSpeed("1/250"), 1.0 / 250);
  EXPECT_DOUBLE_EQ(*ParseShutterSpeed("1/8000s"), 1.0 / 8000);
  EXPECT_DOUBLE_EQ(*ParseShutterSpeed("0.3"), 0.3);
  EXPECT_DOUBLE_EQ(*ParseShutterSpeed("30"), 30.0);
  EXPECT_DOUBLE_EQ(*ParseShutterSpeed("1\"3"), 1.3);
  EXPECT_DOUBLE_EQ(*ParseShutterSpeed("10/10"), 1.0);  // Nikon's shutterspeed2 style
  EXPECT_DOUBLE_EQ(*ParseShutterSpeed("2.5s"), 2.5);
  EXPECT_FALSE(ParseShutterSpeed("bulb"));
  EXPECT_FALSE(ParseShutterSpeed("Bulb"));
  EXPECT_FALSE(ParseShutterSpeed("x 1/250"));
  EXPECT_FALSE(ParseShutterSpeed("1/0"));
  EXPECT_FALSE(ParseShutterSpeed(""));
  EXPECT_DOUBLE_EQ(*ParseIso("1600"), 1600.0);
  EXPECT_FALSE(ParseIso("Auto"));
  EXPECT_FALSE(ParseIso("Auto ISO"));
}

TEST(Gphoto2ParseTest, NearestInLogSpace) {
  const std::vector<std::optional<double>> values = {std::nullopt, 0.25, 0.5, 1.0};
  EXPECT_EQ(NearestInLogSpace(values, 0.3), 1);   // |log 1.2| < |log 1.67|
  EXPECT_EQ(NearestInLogSpace(values, 0.36), 2);  // ratio 1.39 to 0.5 beats 1.44 to 0.25
  EXPECT_EQ(NearestInLogSpace(values, 100.0), 3);
  EXPECT_EQ(NearestInLogSpace({std::nullopt}, 1.0), -1);
}

TEST(Gphoto2DriverTest, OpeningSelectsTheLargestFineJpeg) {
  auto state = Canon30D();
  Gphoto2Camera camera(std::make_unique<FakeGphoto2Session>(state));
  EXPECT_EQ(state->writes, std::vector<std::string>{"imageformat=Large Fine JPEG"});
  const CameraInfo info = camera.Info();
  EXPECT_EQ(info.id, "gphoto2:usb:001,004");
  EXPECT_DOUBLE_EQ(info.min_exposure_s, 1.0 / 8000);
  EXPECT_DOUBLE_EQ(info.max_exposure_s, 30.0);
}

TEST(Gphoto2DriverTest, ChoosesNearestShutterAndIsoAndReportsThem) {
  auto state = Canon30D();
  Gphoto2Camera camera(std::make_unique<FakeGphoto2Session>(state));
  state->writes.clear();
  camera.SetExposure({0.3, 3.0});  // 0.3 s -> 1/4; ISO 300 -> 400 (log-nearer than 200)
  EXPECT_EQ(state->writes, (std::vector<std::string>{"shutterspeed=1/4", "iso=400"}));
  const Frame frame = camera.Capture();
  EXPECT_DOUBLE_EQ(frame.exposure_s, 0.25);
  EXPECT_DOUBLE_EQ(frame.gain, 4.0);
  EXPECT_EQ(frame.width, 24);
  EXPECT_EQ(frame.height, 16);
  EXPECT_EQ(frame.channels, 3);
  EXPECT_FALSE(frame.linear);
  EXPECT_TRUE(state->last_delete);

  state->writes.clear();
  camera.SetExposure({0.26, 3.5});  // same choices: nothing rewritten
  EXPECT_TRUE(state->writes.empty());
  camera.SetExposure({35.0, 1.0});  // within a third of a stop of 30 s
  EXPECT_EQ(state->writes, (std::vector<std::string>{"shutterspeed=30", "iso=100"}));
}

TEST(Gphoto2DriverTest, RejectsExposuresOutsideTheListedRange) {
  auto state = Canon30D();
  Gphoto2Camera camera(std::make_unique<FakeGphoto2Session>(state));
  ExpectError(common::ErrorKind::kInvalidInput, "outside the listed shutter speeds", [&] { camera.SetExposure({60.0, 1.0}); });
  ExpectError(common::ErrorKind::kInvalidInput, "outside", [&] { camera.SetExposure({1e-5, 1.0}); });
  ExpectError(common::ErrorKind::kInvalidInput, "before SetExposure", [&] { camera.Capture(); });
}

TEST(Gphoto2DriverTest, RawOnlyCaptureIsAClearError) {
  auto state = Canon30D();
  state->next_capture.pop_back();
  Gphoto2Camera camera(std::make_unique<FakeGphoto2Session>(state));
  camera.SetExposure({0.01, 1.0});
  ExpectError(common::ErrorKind::kHardware, "IMG_0001.CR2", [&] { camera.Capture(); });
}

TEST(Gphoto2DriverTest, NikonStyleWidgetsAndNoManualMode) {
  auto state = std::make_shared<FakeGphoto2Session::State>();
  state->widgets["shutterspeed2"] = {"1/4000", "1/2", "10/10", "Bulb"};
  state->widgets["imagequality"] = {"NEF (Raw)", "JPEG Basic", "JPEG Fine", "NEF+Fine"};
  state->next_capture = {{"DSC_0001.JPG", "image/jpeg", testing::EncodeTestJpeg(8, 8)}};
  Gphoto2Camera camera(std::make_unique<FakeGphoto2Session>(state));
  EXPECT_EQ(state->writes, std::vector<std::string>{"imagequality=JPEG Fine"});
  camera.SetExposure({0.9, 1.0});
  EXPECT_EQ(state->values["shutterspeed2"], "10/10");
  ExpectError(common::ErrorKind::kInvalidInput, "ISO", [&] { camera.SetExposure({0.9, 2.0}); });

  auto auto_only = std::make_shared<FakeGphoto2Session::State>();
  auto_only->widgets["shutterspeed"] = {"auto"};
  Gphoto2Camera automatic(std::make_unique<FakeGphoto2Session>(auto_only));
  ExpectError(common::ErrorKind::kHardware, "mode dial", [&] { automatic.SetExposure({0.01, 1.0}); });
}

TEST(Gphoto2RealTest, CapturesFromAConnectedCamera) {
  std::vector<CameraInfo> cameras;
  try {
    cameras = ListGphoto2Cameras();
  } catch (const common::Error& error) {
    GTEST_SKIP() << "libgphoto2 unavailable: " << error.what();
  }
  if (cameras.empty()) GTEST_SKIP() << "no tethered camera connected";
  auto camera = OpenGphoto2Camera(cameras.front().id.substr(8), {false, true});
  camera->SetExposure({0.01, 1.0});
  EXPECT_GT(camera->Capture().width, 0);
}

}  // namespace
}  // namespace svbtdf::acquire
