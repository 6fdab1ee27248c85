// Fuzzes the simulator's truth/rig.json (docs/truth-format.md), which `compare` and `render` read.
#include "fuzz_support.h"
#include "svbtdf/simulate/truth_io.h"

namespace {
std::filesystem::path rig_file;
}

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  rig_file = svbtdf::fuzz::ScratchFolder() / "rig.json";
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  svbtdf::fuzz::WriteInput(rig_file, data, size);
  svbtdf::fuzz::ExpectOnlySvbtdfErrors([] { (void)svbtdf::simulate::ReadRigTruth(rig_file); });
  return 0;
}
