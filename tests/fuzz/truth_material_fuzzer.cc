// Fuzzes the simulator's truth/material.json (docs/truth-format.md) beside valid maps, then builds
// the truth every texel as the renderer and `compare` do.
#include "fuzz_support.h"
#include "svbtdf/simulate/truth_io.h"
#include "svbtdf/simulate/truth_material.h"

namespace {

std::filesystem::path truth_folder;

void ReadAndBuild() {
  const svbtdf::simulate::MaterialTruth truth = svbtdf::simulate::ReadMaterialTruth(truth_folder);
  for (int y = 0; y < truth.height(); ++y) {
    for (int x = 0; x < truth.width(); ++x) (void)truth.TexelNdf(x, y);
  }
  (void)truth.ToTruthMaterial();
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  truth_folder = svbtdf::fuzz::ScratchFolder() / "truth";
  std::filesystem::create_directories(truth_folder);  // the simulator's truth/ exists before its maps
  svbtdf::simulate::WriteMaterialTruth(truth_folder, svbtdf::simulate::TruthMaterial::FromPattern("rice-paper", 4, 3, 1.5, 1));
  svbtdf::fuzz::RequireFixtureReads("the rice-paper truth", ReadAndBuild);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  svbtdf::fuzz::WriteInput(truth_folder / "material.json", data, size);
  svbtdf::fuzz::ExpectOnlySvbtdfErrors(ReadAndBuild);
  return 0;
}
