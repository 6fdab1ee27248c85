// Fuzzes the simulator's truth/rig.json (docs/truth-format.md), which `compare` and `render` read.
#include "fuzz_support.h"
#include "svbtdf/simulate/truth_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  svbtdf::fuzz::FuzzFile("rig.json", data, size, [](const std::filesystem::path& path) { (void)svbtdf::simulate::ReadRigTruth(path); });
  return 0;
}
