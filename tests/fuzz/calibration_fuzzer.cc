// Fuzzes calibration.json (docs/calibration-format.md), which `calibrate` writes and a user may
// hand to `process --calibration`.
#include "fuzz_support.h"
#include "svbtdf/calib/session_calibration.h"

namespace {
std::filesystem::path calibration_file;
}

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  calibration_file = svbtdf::fuzz::ScratchFolder() / "calibration.json";
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  svbtdf::fuzz::WriteInput(calibration_file, data, size);
  svbtdf::fuzz::ExpectOnlySvbtdfErrors([] { (void)svbtdf::calib::ReadSessionCalibration(calibration_file); });
  return 0;
}
