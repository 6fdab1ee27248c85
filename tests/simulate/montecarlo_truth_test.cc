// Tests of the Monte Carlo slab truth (simulate/montecarlo_truth.h, docs/truth-format.md): it is
// the traced slices at the traced view directions, statistically consistent with an independent
// trace, continuous between them, deterministic, written and read back exactly, and the reader
// names the file at fault. The end-to-end `simulate --truth montecarlo` run is here too.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/session/session.h"
#include "svbtdf/simulate/montecarlo_truth.h"
#include "svbtdf/simulate/presets.h"
#include "svbtdf/acquire/simulated_session.h"
#include "svbtdf/simulate/truth_io.h"
#include "temp_folder.h"

namespace svbtdf::simulate {
namespace {
namespace fs = std::filesystem;

// The tiny preset's camera over its sample: view directions 45 degrees from vertical, spread by
// a few degrees across the sample.
ViewGrid TinyViews() {
  const SimulationPreset preset = MakePreset("tiny");
  return ViewGrid::Spanning(Rig(preset.rig).camera().Centre(), preset.rig.sample, 3);
}

MonteCarloTruth SmallTruth(uint64_t seed, int threads = 2, int64_t paths = int64_t{1} << 16) {
  std::vector<SlabMaterial> materials = DefaultSlabMaterials();
  std::vector<int> index = SlabIndexMap(8, 6, static_cast<int>(materials.size()), seed);
  return MonteCarloTruth::Trace(8, 6, 1.5, std::move(materials), std::move(index), TinyViews(),
                                {16, paths, 100}, seed, threads, false);
}

// The first texel of each material.
std::vector<int> TexelPerMaterial(const MonteCarloTruth& truth) {
  std::vector<int> texels(truth.materials().size(), -1);
  for (int t = 0; t < truth.num_texels(); ++t) {
    if (texels[truth.material_of(t)] < 0) texels[truth.material_of(t)] = t;
  }
  return texels;
}

TEST(MonteCarloTruth, ViewGridSpansTheSampleAndInterpolatesExactlyAtNodes) {
  const ViewGrid views = TinyViews();
  const SimulationPreset preset = MakePreset("tiny");
  const model::Vec3 camera = Rig(preset.rig).camera().Centre();
  // The sample spans a few degrees of view direction; every texel's o lies inside the grid.
  const double spread = std::acos(views.Node(0).dot(views.Node(views.num_nodes() - 1)));
  EXPECT_GT(spread, 2.0 * model::kPi / 180);
  EXPECT_LT(spread, 10.0 * model::kPi / 180);
  for (const model::Vec3& p : {model::Vec3(-0.04, 0.04, 0), model::Vec3(0.04, -0.04, 0), model::Vec3(0, 0, 0)}) {
    const model::Vec3 o = (camera - p).normalized();
    EXPECT_GT(o.x(), views.x0);
    EXPECT_LT(o.x(), views.x1);
    EXPECT_GT(o.y(), views.y0);
    EXPECT_LT(o.y(), views.y1);
  }
  for (int node = 0; node < views.num_nodes(); ++node) {
    double weight = 0;
    for (const auto& [n, w] : views.Interpolation(views.Node(node))) weight += n == node ? w : 0.0;
    EXPECT_NEAR(weight, 1.0, 1e-12) << node;
  }
}

// At a traced view direction and a cell centre, the truth is the tabulated cell mean (tint
// included) plus rho_d; and the table agrees, within its standard errors, with an independent
// trace of the same slab with another seed.
TEST(MonteCarloTruth, AtGridNodesItIsTheTracedSliceWithinItsStandardError) {
  const MonteCarloTruth truth = SmallTruth(3, 2, int64_t{1} << 18);
  const model::Hemicube& grid = truth.hemicube();
  const std::vector<int> texels = TexelPerMaterial(truth);
  for (int m = 0; m < static_cast<int>(texels.size()); ++m) {
    ASSERT_GE(texels[m], 0) << "material " << m << " missing from the layout";
    for (int node : {0, 4, 8}) {
      const model::Vec3 o = truth.views().Node(node);
      for (int cell = 0; cell < grid.num_cells(); cell += 7) {
        const model::Rgb value = truth.Evaluate(texels[m], model::FlipZ(grid.CellCenter(cell)), o);
        for (int c = 0; c < 3; ++c) {
          const double expected = truth.SliceValue(m, node, cell)[c] + truth.rho_d(texels[m])[c];
          EXPECT_NEAR(value[c], expected, 1e-6 * expected + 1e-9) << m << " " << node << " " << cell;
        }
      }
    }
  }
  // Independent trace of material 1 at the centre node.
  SliceOptions options;
  options.paths = int64_t{1} << 18;
  options.seed = 12345;
  options.threads = 2;
  const SlabMaterial& material = truth.materials()[1];
  const BtdfSlice slice = SlabTracer(material.ToSlab(1.5)).SliceForView(truth.views().Node(4), grid, options);
  double chi2 = 0;
  int dof = 0, beyond_4_sigma = 0;
  for (int cell = 0; cell < grid.num_cells(); ++cell) {
    if (slice.hits[cell] < 200) continue;  // the normal approximation of the error needs hits
    const double a = truth.SliceValue(1, 4, cell)[0] / material.tint[0];
    const double sa = truth.SliceError(1, 4, cell)[0] / material.tint[0];
    const double z2 = model::Square(a - slice.rho[cell]) / (model::Square(sa) + model::Square(slice.standard_error[cell]));
    chi2 += z2;
    beyond_4_sigma += z2 > 16;
    ++dof;
  }
  ASSERT_GT(dof, 50);
  std::printf("independent trace: chi^2/dof %.3f over %d cells, %d beyond 4 sigma\n", chi2 / dof, dof, beyond_4_sigma);
  EXPECT_NEAR(chi2 / dof, 1.0, 5 * std::sqrt(2.0 / dof)) << "over " << dof << " cells";
  EXPECT_LE(beyond_4_sigma, 1);
}

// Between nodes the truth is continuous in o (bilinear in view) and in i (bilinear over the
// hemicube, across cell edges and face seams): halving the step halves the largest jump, which a
// discontinuity would not allow.
TEST(MonteCarloTruth, ContinuousInViewAndLightDirections) {
  const MonteCarloTruth truth = SmallTruth(4);
  const int texel = TexelPerMaterial(truth)[2];
  const ViewGrid& v = truth.views();
  const model::Vec3 i = model::Vec3(0.1, 0.45, -1).normalized();
  const auto largest_jump = [&](int steps, auto&& path) {
    double jump = 0, scale = 0;
    model::Rgb previous = path(0.0);
    for (int k = 1; k <= steps; ++k) {
      const model::Rgb value = path(static_cast<double>(k) / steps);
      jump = std::max(jump, std::abs(value[1] - previous[1]));
      scale = std::max(scale, value[1]);
      previous = value;
    }
    return jump / scale;
  };
  // o along a diagonal through the whole grid and beyond it (clamped outside).
  const auto view_path = [&](double t) {
    const double ox = v.x0 - 0.1 * (v.x1 - v.x0) + 1.2 * t * (v.x1 - v.x0);
    const double oy = v.y0 - 0.1 * (v.y1 - v.y0) + 1.2 * t * (v.y1 - v.y0);
    return truth.Evaluate(texel, i, model::Vec3(ox, oy, std::sqrt(1 - ox * ox - oy * oy)));
  };
  // i sweeping from the top face across the seam onto the +y side face of FlipZ(i).
  const auto light_path = [&](double t) {
    const double angle = (20 + 60 * t) * model::kPi / 180;
    return truth.Evaluate(texel, model::Vec3(0.05, std::sin(angle), -std::cos(angle)), v.Node(4));
  };
  for (const auto& path : {std::function<model::Rgb(double)>(view_path), std::function<model::Rgb(double)>(light_path)}) {
    const double coarse = largest_jump(2000, path), fine = largest_jump(4000, path);
    std::printf("largest relative jump: %.2e (2000 steps), %.2e (4000 steps)\n", coarse, fine);
    EXPECT_LT(coarse, 0.01);
    EXPECT_LT(fine, 0.6 * coarse);
  }
}

TEST(MonteCarloTruth, DeterministicForTheSeedWhateverTheThreads) {
  const MonteCarloTruth a = SmallTruth(5, 1), b = SmallTruth(5, 2), c = SmallTruth(6, 2);
  int differ = 0;
  for (int m = 0; m < 3; ++m) {
    for (int cell = 0; cell < a.hemicube().num_cells(); ++cell) {
      EXPECT_EQ(a.SliceValue(m, 4, cell), b.SliceValue(m, 4, cell));
      EXPECT_EQ(a.SliceError(m, 4, cell), b.SliceError(m, 4, cell));
      differ += a.SliceValue(m, 4, cell) != c.SliceValue(m, 4, cell);
    }
  }
  EXPECT_GT(differ, 100);  // another seed traces other paths
}

class MonteCarloTruthFiles : public ::testing::Test {
 protected:
  // The error message of reading the truth, which must be an svbtdf::Error.
  std::string ReadError() {
    try {
      ReadMonteCarloTruth(folder_);
    } catch (const common::Error& e) {
      return e.what();
    }
    ADD_FAILURE() << "a malformed truth was accepted";
    return {};
  }
  void EditManifest(const std::function<void(nlohmann::json&)>& edit) {
    nlohmann::json manifest = nlohmann::json::parse(common::ReadTextFile(folder_ / "material.json"));
    edit(manifest);
    common::WriteTextAtomically(folder_ / "material.json", manifest.dump(), /*overwrite=*/true);
  }
  svbtdf::testing::TempFolder temp_;
  const fs::path folder_ = temp_.path();
};

TEST_F(MonteCarloTruthFiles, RoundTripIsExact) {
  const MonteCarloTruth truth = SmallTruth(8);
  WriteMonteCarloTruth(folder_, truth);
  EXPECT_EQ(ReadTruthKind(folder_), "montecarlo");
  const MonteCarloTruth back = ReadMonteCarloTruth(folder_);
  EXPECT_EQ(back.seed, 8u);
  EXPECT_EQ(back.precision.paths, truth.precision.paths);
  ASSERT_EQ(back.materials().size(), truth.materials().size());
  EXPECT_EQ(back.materials()[2].entry.ndf, "ellipsoid");
  for (int t = 0; t < truth.num_texels(); ++t) {
    EXPECT_EQ(back.material_of(t), truth.material_of(t));
    for (const model::Vec3& i : {model::Vec3(0.2, 0.5, -1).normalized(), model::Vec3(-0.6, 0.1, -0.4).normalized()}) {
      const model::Vec3 o = model::Vec3(0.01, -0.7, 0.71).normalized();
      EXPECT_EQ(back.Evaluate(t, i, o), truth.Evaluate(t, i, o)) << t;
    }
  }
  // Never overwritten.
  EXPECT_THROW(WriteMonteCarloTruth(folder_, truth), common::Error);
  // The analytic reader refuses it, naming the manifest.
  try {
    ReadMaterialTruth(folder_);
    ADD_FAILURE() << "read as analytic";
  } catch (const common::Error& e) {
    EXPECT_NE(std::string(e.what()).find("material.json"), std::string::npos) << e.what();
  }
}

TEST_F(MonteCarloTruthFiles, MalformedFilesAreRejectedNamingTheFile) {
  WriteMonteCarloTruth(folder_, SmallTruth(9));
  const std::string good = common::ReadTextFile(folder_ / "material.json");
  const auto restore = [&] { common::WriteTextAtomically(folder_ / "material.json", good, true); };
  const auto expect_named = [&](const std::string& file, const std::string& what) {
    const std::string message = ReadError();
    EXPECT_NE(message.find(file), std::string::npos) << what << ": " << message;
  };

  common::WriteTextAtomically(folder_ / "material.json", "{\"format\": \"svbtdf-truth-material\", ", true);
  expect_named("material.json", "truncated JSON");
  restore();
  EditManifest([](nlohmann::json& m) { m["ndf"]["kind"] = "analytic"; });
  expect_named("material.json", "another kind");
  restore();
  EditManifest([](nlohmann::json& m) { m.erase("view_grid"); });
  expect_named("material.json", "missing key");
  restore();
  EditManifest([](nlohmann::json& m) { m["materials"][0]["entry"]["ndf"] = "phong"; });
  expect_named("material.json", "unknown NDF");
  restore();
  EditManifest([](nlohmann::json& m) { m["hemicube_resolution"] = 32; });
  expect_named("slices.exr", "slices of another resolution");
  restore();

  const common::FloatImage index = common::ReadFloatImage(folder_ / "index.exr");
  common::FloatImage bad_index = index;
  bad_index.pixels[5] = 7.0f;
  common::WriteFloatImage(folder_ / "index.exr", bad_index, false, true);
  expect_named("index.exr", "material index out of range");
  common::WriteFloatImage(folder_ / "index.exr", index, false, true);

  const common::FloatImage slices = common::ReadFloatImage(folder_ / "slices.exr");
  common::FloatImage negative = slices;
  negative.pixels[10] = -1.0f;
  common::WriteFloatImage(folder_ / "slices.exr", negative, false, true);
  expect_named(folder_.string(), "negative slice value");
  fs::remove(folder_ / "slices.exr");
  expect_named("slices.exr", "missing slices");
  common::WriteFloatImage(folder_ / "slices.exr", slices, false, true);
  EXPECT_NO_THROW(ReadMonteCarloTruth(folder_));
}

// `svbtdf simulate --truth montecarlo --preset tiny`: a complete session whose truth reads back
// as the Monte Carlo truth of the preset, with every material in view; rerun from its truth, the
// same images.
TEST(SimulateMonteCarlo, TinyPresetWritesAReadableTruth) {
  const svbtdf::testing::TempFolder temp;
  const fs::path out = temp / "out";
  SimulationOptions options;
  options.preset = "tiny";
  options.truth = "montecarlo";
  options.seed = 2;
  options.threads = 2;
  options.progress = false;
  const acquire::SimulationOutput result = acquire::SimulateSession(out, options);
  EXPECT_TRUE(session::Session::Open(result.session).Verify().complete());
  EXPECT_EQ(ReadRigTruth(result.truth / "rig.json").capture.truth_kind, "montecarlo");
  const MonteCarloTruth truth = ReadMonteCarloTruth(result.truth);
  EXPECT_EQ(truth.texels_x(), 32);
  EXPECT_EQ(truth.eta(), 1.5);
  EXPECT_EQ(truth.seed, 2u);
  EXPECT_EQ(truth.precision.hemicube_resolution, MakePreset("tiny").montecarlo.hemicube_resolution);
  // The preset's precision: the cells holding 90% of each slice's energy within 10% (about 6%).
  EXPECT_LT(truth.dominant_relative_error, 0.10);
  std::vector<int> count(truth.materials().size(), 0);
  for (int t = 0; t < truth.num_texels(); ++t) ++count[truth.material_of(t)];
  for (int c : count) EXPECT_GT(c, 50);
  // A complete simulation is never redone: of the same settings it is done already.
  EXPECT_TRUE(acquire::SimulateSession(out, options).already_complete);
  // Without its session, the folder is an unfinished simulation: the truth is read back, not
  // traced again, and renders exactly the same images (what resuming an interrupted run relies on).
  const fs::path first_folder = temp / "out-first";
  fs::rename(result.session, first_folder);
  const session::Session first = session::Session::Open(first_folder);
  const std::string manifest = common::ReadTextFile(result.truth / "material.json");
  acquire::SimulateSession(out, options);
  EXPECT_EQ(common::ReadTextFile(result.truth / "material.json"), manifest);
  const session::Session second = session::Session::Open(result.session);
  ASSERT_EQ(first.entries().size(), second.entries().size());
  for (const session::SessionEntry& entry : first.entries()) EXPECT_EQ(entry.crc32, second.Entry(entry.key).crc32) << entry.key;
  // A truth of other settings in the folder is refused rather than rendered.
  fs::remove_all(result.session);
  options.seed = 3;
  EXPECT_THROW(acquire::SimulateSession(out, options), common::Error);
}

}  // namespace
}  // namespace svbtdf::simulate
