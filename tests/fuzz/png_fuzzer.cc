// Fuzzes the camera images a session holds (PNG; docs/session-format.md): decoding is
// OpenImageIO's and libpng's, the checks around it (header sizes, bit depth, channels) ours.
#include "fuzz_support.h"
#include "svbtdf/common/image_io.h"

namespace {
std::filesystem::path image_file;
}

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  image_file = svbtdf::fuzz::ScratchFolder() / "image.png";
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  svbtdf::fuzz::WriteInput(image_file, data, size);
  svbtdf::fuzz::ExpectOnlySvbtdfErrors([] { (void)svbtdf::common::ReadCameraImage(image_file); });
  return 0;
}
