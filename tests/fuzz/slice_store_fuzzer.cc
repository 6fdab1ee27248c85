// Fuzzes a slice store's processed.json (docs/slice-store.md) beside valid samples and maps, then
// reads the first and last texel's samples, slice and fit input as `fit` does.
#include <vector>

#include "analytic_store.h"
#include "fuzz_support.h"
#include "svbtdf/fit/slice_store.h"

namespace {

std::filesystem::path store_folder;

void OpenAndRead() {
  const svbtdf::fit::SliceStore store = svbtdf::fit::SliceStore::Open(store_folder);
  const int64_t texels = static_cast<int64_t>(store.info().texels_x) * store.info().texels_y;
  std::vector<float> samples;
  std::vector<float> slice(store.light_grid().num_cells());
  for (int64_t texel : {int64_t{0}, texels - 1}) {
    store.ReadSamples(texel, &samples);
    store.ReadSlice(texel, slice.data());
    (void)store.MakeTexelSlice(texel);
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  store_folder = svbtdf::fuzz::ScratchFolder() / "processed";
  svbtdf::testing::AnalyticMaterial truth;
  truth.width = 5;
  truth.height = 4;
  svbtdf::testing::WriteAnalyticStore(store_folder, truth, /*dots_per_side=*/4, /*noise=*/0.0, 1.5, 7, /*tile_texels=*/8);
  svbtdf::fuzz::RequireFixtureReads("the analytic store", OpenAndRead);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  svbtdf::fuzz::WriteInput(store_folder / "processed.json", data, size);
  svbtdf::fuzz::ExpectOnlySvbtdfErrors(OpenAndRead);
  return 0;
}
