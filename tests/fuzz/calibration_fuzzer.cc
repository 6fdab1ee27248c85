// Fuzzes calibration.json (docs/calibration-format.md), which `calibrate` writes and a user may
// hand to `process --calibration`.
#include "fuzz_support.h"
#include "svbtdf/calib/session_calibration.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  svbtdf::fuzz::FuzzFile("calibration.json", data, size, [](const std::filesystem::path& path) { (void)svbtdf::calib::ReadSessionCalibration(path); });
  return 0;
}
