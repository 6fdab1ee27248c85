// Fuzzes the OpenEXR maps of materials, truths and slice stores: decoding is OpenImageIO's and
// OpenEXR's, the checks around it (header sizes, finite values) ours.
#include "fuzz_support.h"
#include "svbtdf/common/image_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  svbtdf::fuzz::FuzzFile("map.exr", data, size, [](const std::filesystem::path& path) {
    svbtdf::common::RequireFinite(svbtdf::common::ReadFloatImage(path), path.string());
  });
  return 0;
}
