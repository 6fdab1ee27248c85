// Fuzzes the OpenEXR maps of materials, truths and slice stores: decoding is OpenImageIO's and
// OpenEXR's, the checks around it (header sizes, finite values) ours.
#include "fuzz_support.h"
#include "svbtdf/common/image_io.h"

namespace {
std::filesystem::path image_file;
}

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  image_file = svbtdf::fuzz::ScratchFolder() / "map.exr";
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  svbtdf::fuzz::WriteInput(image_file, data, size);
  svbtdf::fuzz::ExpectOnlySvbtdfErrors([] {
    const svbtdf::common::FloatImage image = svbtdf::common::ReadFloatImage(image_file);
    svbtdf::common::RequireFinite(image, image_file.string());
  });
  return 0;
}
