// Fuzzes a material's material.json (docs/material-format.md) beside valid maps, then evaluates
// every texel: an index or size the manifest gives (representatives.texels = 1e9, -1) must be
// refused when read, not met as an out-of-bounds read when evaluating.
#include "fuzz_support.h"
#include "small_material.h"
#include "svbtdf/fit/material.h"

namespace {

std::filesystem::path material_folder;

void ReadAndEvaluate() {
  const svbtdf::fit::Material material = svbtdf::fit::ReadMaterial(material_folder);
  const svbtdf::fit::MaterialEvaluator evaluator(material);
  const svbtdf::model::Vec3 light(0.1, -0.2, -0.97), view(0.0, 0.3, 0.95);
  for (int y = 0; y < material.height; ++y) {
    for (int x = 0; x < material.width; ++x) (void)evaluator.Evaluate(x, y, light.normalized(), view.normalized());
  }
  (void)svbtdf::fit::RepresentativeScales(material);
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  material_folder = svbtdf::fuzz::ScratchFolder() / "material";
  svbtdf::fit::Material material = svbtdf::SmallMaterial(4, 3);
  material.width_m = material.height_m = 0.01;
  svbtdf::fit::WriteMaterial(material_folder, material);
  svbtdf::fuzz::RequireFixtureReads("SmallMaterial", ReadAndEvaluate);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  svbtdf::fuzz::WriteInput(material_folder / "material.json", data, size);
  svbtdf::fuzz::ExpectOnlySvbtdfErrors(ReadAndEvaluate);
  return 0;
}
