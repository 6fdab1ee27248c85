// Fuzzes the camera images a session holds (PNG; docs/session-format.md): decoding is
// OpenImageIO's and libpng's, the checks around it (header sizes, bit depth, channels) ours.
#include "fuzz_support.h"
#include "svbtdf/common/image_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  svbtdf::fuzz::FuzzFile("image.png", data, size, [](const std::filesystem::path& path) { (void)svbtdf::common::ReadCameraImage(path); });
  return 0;
}
