// The device factory: every spec that names no device is one clear error naming the option.
#include <gtest/gtest.h>

#include <string>

#include "svbtdf/acquire/lab_rig.h"
#include "svbtdf/common/error.h"
#include "temp_folder.h"

namespace svbtdf::acquire {
namespace {

// The message of the Error that opening the rig throws ("" when it opens).
std::string OpenError(const std::string& camera, const std::string& display) {
  try {
    OpenLabRig(camera, display, "as-is");
  } catch (const common::Error& e) {
    return e.what();
  }
  return "";
}

TEST(LabRig, ACameraSpecThatNamesNoCameraIsRefusedNamingTheOption) {
  for (const char* spec : {"", "webcam", "v4l2", "v4l2:", "libcamera:", "sim:", "usb:/dev/video0"}) {
    const std::string message = OpenError(spec, "sim");
    EXPECT_NE(message.find("--camera"), std::string::npos) << spec << ": " << message;
    EXPECT_NE(message.find("is not a camera"), std::string::npos) << spec << ": " << message;
  }
}

TEST(LabRig, AMissingDeviceNamesItsPath) {
  const std::string message = OpenError("v4l2:/nonexistent/video9", "sim");
  EXPECT_NE(message.find("/nonexistent/video9"), std::string::npos) << message;
}

TEST(LabRig, ASimulatedCameraNeedsASimulation) {
  const testing::TempFolder folder;
  const std::string message = OpenError("sim:" + folder.path().string(), "sim");
  EXPECT_NE(message.find("svbtdf simulate"), std::string::npos) << message;
}

}  // namespace
}  // namespace svbtdf::acquire
