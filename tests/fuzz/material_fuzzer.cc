// Fuzzes a material's material.json (docs/material-format.md) beside valid maps (a dual-microfacet
// material's and a slab material's), then evaluates every texel: an index or size the manifest gives (representatives.texels = 1e9, -1) must be
// refused when read, not met as an out-of-bounds read when evaluating.
#include <string>

#include "fuzz_support.h"
#include "small_material.h"
#include "svbtdf/common/image_io.h"
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
  // A slab material's maps too (unused by the dual manifest), so that a manifest saying "slab"
  // (corpus/material/slab.json) reads whole and evaluates two rough interfaces.
  const auto map = [&](const char* name, float value) {
    svbtdf::common::WriteFloatImage(material_folder / name, svbtdf::common::FloatImage(4, 3, 1, value), false);
  };
  for (const char* side : {"entry", "exit"}) {
    const std::string prefix = std::string("slab_") + side;
    map((prefix + "_alpha_x.exr").c_str(), 0.3f);
    map((prefix + "_alpha_y.exr").c_str(), 0.1f);
    map((prefix + "_azimuth.exr").c_str(), 0.4f);
    map((prefix + "_roughness_se.exr").c_str(), 0.01f);
  }
  map("slab_internal_reflection.exr", 1.0f);
  map("slab_longer_paths.exr", 0.5f);  // version 6 (corpus/material/slab-longer-paths.json)
  svbtdf::fuzz::RequireFixtureReads("SmallMaterial", ReadAndEvaluate);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  svbtdf::fuzz::WriteInput(material_folder / "material.json", data, size);
  svbtdf::fuzz::ExpectOnlySvbtdfErrors(ReadAndEvaluate);
  return 0;
}
