// The fitted material end to end without images: slices synthesised from known texels are
// clustered, the representatives fitted, the material assembled, written, read back and
// evaluated on held-out light directions (issue 5's acceptance, on a small synthetic material).
#include <gtest/gtest.h>

#include <filesystem>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/json.h"
#include "svbtdf/fit/clustering.h"
#include "svbtdf/fit/material.h"
#include "svbtdf/model/beckmann.h"
#include "svbtdf/model/ggx.h"
#include "svbtdf/model/internal_reflection.h"
#include "synthetic_slices.h"
#include "temp_folder.h"

namespace svbtdf::fit {
namespace {
namespace fs = std::filesystem;

constexpr int kWidth = 8, kHeight = 6;
constexpr int kDots = 32;  // per side of the dot grid

// Three kinds of texel in vertical bands, with a gentle gradient of k_s across each band.
struct SyntheticMaterial {
  std::vector<Truth> truths;
  std::vector<TexelSlice> slices;
  common::FloatImage rho_d{kWidth, kHeight, 3};
};

SyntheticMaterial MakeMaterial(const model::Vec3& view, const RigSamples& rig) {
  const model::Hemicube grid(32);
  SyntheticMaterial m;
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      const int band = x * 3 / kWidth;
      Truth truth = band == 0   ? MakeTruth(grid, model::GgxNdf(0.25, 0.15), 0.3)
                    : band == 1 ? MakeTruth(grid, model::GgxNdf(0.15, 0.15), 0.7)
                                : MakeTruth(grid, model::BeckmannNdf(0.3, 0.2), 0.5);
      truth.k_s = 0.7 + 0.02 * y;
      m.slices.push_back(Synthesize(truth, view, rig, 0.01, 100 + y * kWidth + x));
      m.truths.push_back(std::move(truth));
      for (int c = 0; c < 3; ++c) m.rho_d.at(x, y, c) = 0.01f * c;
    }
  }
  return m;
}

Material FitMaterial(const SyntheticMaterial& synthetic, double representative_fraction) {
  const int dots = static_cast<int>(synthetic.slices.front().rho.size());
  SliceSource source;
  source.num_texels = kWidth * kHeight;
  source.dimension = dots;
  source.read = [&](int64_t t, float* out) {
    for (int k = 0; k < dots; ++k) out[k] = static_cast<float>(synthetic.slices[t].rho[k]);
  };
  ClusteringOptions options;
  options.representative_fraction = representative_fraction;
  options.neighbours = 4;
  const Clustering clustering = ClusterSlices(source, options);
  const TexelFitter fitter(1.5);
  FitWorkspace workspace;
  std::vector<TexelFitResult> fits;
  for (int64_t t : clustering.representatives) fits.push_back(fitter.Fit(synthetic.slices[t], &workspace));
  return AssembleMaterial(kWidth, kHeight, 1.5, 32, clustering, fits, synthetic.rho_d);
}

double HeldOutRelativeRmse(const Material& material, const SyntheticMaterial& synthetic, const model::Vec3& view) {
  const MaterialEvaluator evaluator(material);
  const RigSamples held_out = DotGrid(view, kDots, 0.5);
  double error = 0, norm = 0;
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      const Truth& truth = synthetic.truths[y * kWidth + x];
      const TexelBtdf texel = evaluator.Texel(x, y);
      for (const model::Vec3& i : held_out.light) {
        const double expected = truth.Rho(i, view);
        error += model::Square(texel.Evaluate(i, view)[0] - material.rho_d.at(x, y, 0) - expected);
        norm += model::Square(expected);
      }
    }
  }
  return std::sqrt(error / norm);
}

class MaterialTest : public ::testing::Test {
 protected:
  svbtdf::testing::TempFolder folder_;
  const fs::path dir_ = folder_ / "material";  // not there yet: WriteMaterial creates it
};

TEST_F(MaterialTest, RepresentativesPredictHeldOutLightsAlmostAsWellAsFittingEveryTexel) {
  const model::Vec3 view = model::SphericalDirection(model::kPi / 4, 0.0);
  const SyntheticMaterial synthetic = MakeMaterial(view, DotGrid(view, kDots, 0.0));
  const Material every_texel = FitMaterial(synthetic, 1.0);
  const Material representatives = FitMaterial(synthetic, 0.125);  // 6 of 48 texels
  ASSERT_EQ(representatives.representative_texels.size(), 6u);
  const double error_all = HeldOutRelativeRmse(every_texel, synthetic, view);
  const double error_reps = HeldOutRelativeRmse(representatives, synthetic, view);
  RecordProperty("heldout_all", std::to_string(error_all));
  RecordProperty("heldout_representatives", std::to_string(error_reps));
  EXPECT_LT(error_all, 0.05);
  EXPECT_LT(error_reps, 1.2 * error_all + 0.005) << "all " << error_all << " representatives " << error_reps;
}

TEST_F(MaterialTest, RoundTripsThroughDiskAndNeverOverwrites) {
  const model::Vec3 view = model::SphericalDirection(model::kPi / 4, 0.0);
  const SyntheticMaterial synthetic = MakeMaterial(view, DotGrid(view, 16, 0.0));
  Material material = FitMaterial(synthetic, 0.125);
  material.provenance = {{"test", true}};
  WriteMaterial(dir_, material);
  EXPECT_THROW(WriteMaterial(dir_, material), common::Error);
  const Material read = ReadMaterial(dir_);
  EXPECT_EQ(read.representative_texels, material.representative_texels);
  EXPECT_EQ(read.alpha.pixels, material.alpha.pixels);
  EXPECT_EQ(read.weight_index.pixels, material.weight_index.pixels);
  EXPECT_EQ(read.provenance["test"], true);
  const MaterialEvaluator a(material), b(read);
  const model::Vec3 i = model::FlipZ(model::SphericalDirection(0.6, model::kPi));
  EXPECT_NEAR(a.Evaluate(3, 2, i, view)[1], b.Evaluate(3, 2, i, view)[1], 1e-5 * a.Evaluate(3, 2, i, view)[1]);
  EXPECT_THROW(b.Evaluate(kWidth, 0, i, view), common::Error);
}

TEST_F(MaterialTest, DamagedMaterialsAreErrorsNamingTheFile) {
  const model::Vec3 view = model::SphericalDirection(model::kPi / 4, 0.0);
  const SyntheticMaterial synthetic = MakeMaterial(view, DotGrid(view, 16, 0.0));
  WriteMaterial(dir_, FitMaterial(synthetic, 0.125));
  fs::remove(dir_ / "k_s.exr");
  try {
    ReadMaterial(dir_);
    FAIL();
  } catch (const common::Error& e) {
    EXPECT_NE(std::string(e.what()).find("k_s.exr"), std::string::npos) << e.what();
  }
  common::WriteTextAtomically(dir_ / "material.json", "{\"format\": \"svbtdf-material\", \"version\": 99}");
  try {
    ReadMaterial(dir_);
    FAIL();
  } catch (const common::Error& e) {
    EXPECT_NE(std::string(e.what()).find("version 99"), std::string::npos) << e.what();
  }
  // A representative texel outside the material crashed `svbtdf eval` with SIGSEGV (1e9) or read
  // another texel silently (1024, -1) (issue 15).
  WriteMaterial(dir_ / "indices", FitMaterial(synthetic, 0.125));
  const fs::path manifest = dir_ / "indices" / "material.json";
  nlohmann::json json = common::ReadJsonFile(manifest);
  for (const int64_t texel : {int64_t{1000000000}, static_cast<int64_t>(json["width"].get<int>() * json["height"].get<int>()), int64_t{-1}}) {
    json["representatives"]["texels"][0] = texel;
    common::WriteTextAtomically(manifest, json.dump(), /*overwrite=*/true);
    try {
      ReadMaterial(dir_ / "indices");
      FAIL() << "representative texel " << texel << " was read";
    } catch (const common::Error& e) {
      EXPECT_NE(std::string(e.what()).find("material.json: lists representative texel " + std::to_string(texel)),
                std::string::npos) << e.what();
    }
  }
  // A provenance that is not an object would throw nlohmann's type error in its readers (the
  // quality checks, the report).
  json = common::ReadJsonFile(manifest);
  json["representatives"]["texels"][0] = 0;
  json["provenance"] = 7;
  common::WriteTextAtomically(manifest, json.dump(), /*overwrite=*/true);
  try {
    ReadMaterial(dir_ / "indices");
    FAIL() << "a provenance of 7 was read";
  } catch (const common::Error& e) {
    EXPECT_NE(std::string(e.what()).find("material.json: has a \"provenance\" that is not an object"), std::string::npos)
        << e.what();
  }
  // 150,000 nested [] in the provenance crashed `svbtdf eval` with SIGSEGV (issue 15).
  const std::string deep = std::string(150000, '[') + std::string(150000, ']');
  common::WriteTextAtomically(dir_ / "material.json", "{\"format\": \"svbtdf-material\", \"provenance\": " + deep + "}");
  try {
    ReadMaterial(dir_);
    FAIL();
  } catch (const common::Error& e) {
    EXPECT_EQ(e.kind(), common::ErrorKind::kFormat);
    EXPECT_NE(std::string(e.what()).find("material.json: is not valid JSON: nested deeper"), std::string::npos) << e.what();
  }
}

// Version 3: the standard errors round-trip as maps; a material without them is still written
// as version 1, which older readers read; a manifest that lists them under an older version, or a
// missing map, is refused naming the file.
TEST_F(MaterialTest, StandardErrorsRoundTripAsVersion3) {
  const model::Vec3 view = model::SphericalDirection(model::kPi / 4, 0.0);
  const SyntheticMaterial synthetic = MakeMaterial(view, DotGrid(view, 16, 0.0));
  Material material = FitMaterial(synthetic, 0.125);
  ASSERT_TRUE(material.has_uncertainty());
  // The assembly fills the shadowing roughness's and the NDF width's errors of every texel.
  for (float se : material.shadowing_roughness_se.pixels) EXPECT_GE(se, 0.0f);
  for (const int64_t t : material.representative_texels) {
    EXPECT_GT(material.ndf_width.pixels[t], 0.0f);
    EXPECT_GT(material.ndf_width_se.pixels[t], 0.0f);
  }
  material.alpha_se.at(1, 1) = 0.25f;
  WriteMaterial(dir_ / "v3", material);
  EXPECT_EQ(common::ReadJsonFile(dir_ / "v3" / "material.json")["version"], 3);
  const Material read = ReadMaterial(dir_ / "v3");
  ASSERT_TRUE(read.has_uncertainty());
  EXPECT_EQ(read.alpha_se.pixels, material.alpha_se.pixels);
  EXPECT_EQ(read.k_s_se.pixels, material.k_s_se.pixels);
  EXPECT_EQ(read.rho_d_se.pixels, material.rho_d_se.pixels);
  EXPECT_EQ(read.shadowing_roughness_se.pixels, material.shadowing_roughness_se.pixels);
  EXPECT_EQ(read.ndf_width_se.pixels, material.ndf_width_se.pixels);
  EXPECT_EQ(read.prediction_se.pixels, material.prediction_se.pixels);

  Material without = material;
  for (common::FloatImage* map : {&without.alpha_se, &without.k_s_se, &without.rho_d_se, &without.shadowing_roughness_se,
                                  &without.ndf_width, &without.ndf_width_se, &without.prediction_se}) {
    *map = common::FloatImage();
  }
  WriteMaterial(dir_ / "v1", without);
  EXPECT_EQ(common::ReadJsonFile(dir_ / "v1" / "material.json")["version"], 1);
  EXPECT_FALSE(fs::exists(dir_ / "v1" / "alpha_se.exr"));
  EXPECT_FALSE(ReadMaterial(dir_ / "v1").has_uncertainty());

  const fs::path manifest = dir_ / "v3" / "material.json";
  nlohmann::json json = common::ReadJsonFile(manifest);
  json["version"] = 2;
  common::WriteTextAtomically(manifest, json.dump(), /*overwrite=*/true);
  try {
    ReadMaterial(dir_ / "v3");
    FAIL() << "standard errors under version 2 were read";
  } catch (const common::Error& e) {
    EXPECT_NE(std::string(e.what()).find("version 3"), std::string::npos) << e.what();
  }
  json["version"] = 3;
  common::WriteTextAtomically(manifest, json.dump(), /*overwrite=*/true);
  fs::remove(dir_ / "v3" / "rho_d_se.exr");
  try {
    ReadMaterial(dir_ / "v3");
    FAIL() << "a missing standard-error map was not noticed";
  } catch (const common::Error& e) {
    EXPECT_NE(std::string(e.what()).find("rho_d_se.exr"), std::string::npos) << e.what();
  }
}

// Version 4: a material with the internal-reflection term says so in its manifest, every
// evaluator adds the term (TexelParams), and an older version or another model with it is refused.
TEST_F(MaterialTest, InternalReflectionRoundTripsAsVersion4AndIsEvaluated) {
  const model::Vec3 view = model::SphericalDirection(model::kPi / 4, 0.0);
  const SyntheticMaterial synthetic = MakeMaterial(view, DotGrid(view, 16, 0.0));
  Material material = FitMaterial(synthetic, 0.125);
  material.internal_reflection = true;
  WriteMaterial(dir_ / "v4", material);
  const fs::path manifest = dir_ / "v4" / "material.json";
  EXPECT_EQ(common::ReadJsonFile(manifest)["version"], 4);
  const Material read = ReadMaterial(dir_ / "v4");
  ASSERT_TRUE(read.internal_reflection);

  const MaterialEvaluator evaluator(read);
  const TexelBtdf texel = evaluator.Texel(2, 3);
  ASSERT_TRUE(texel.params().internal_reflection);
  model::DualMicrofacetParams direct_only = texel.params();
  direct_only.internal_reflection = false;
  const model::InternalReflection paths(read.eta);
  const model::Vec3 light = model::FlipZ(model::SphericalDirection(0.9, 2.5));  // far from the lobe
  const double term = paths.Blend(texel.ndf(), texel.params().alpha, light, view);
  ASSERT_GT(term, 0.0);
  const model::Rgb with = texel.Evaluate(light, view);
  const model::Rgb without = model::EvaluateMaterial(texel.ndf(), direct_only, light, view);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(with[c] - without[c], texel.params().k_s[c] * term, 1e-12 + 1e-9 * with[c]);

  nlohmann::json json = common::ReadJsonFile(manifest);
  for (const auto& [version, btdf] : {std::pair{3, "dual-microfacet"}, {4, "walter-ggx"}}) {
    json["version"] = version;
    json["btdf"] = btdf;
    common::WriteTextAtomically(manifest, json.dump(), /*overwrite=*/true);
    try {
      ReadMaterial(dir_ / "v4");
      FAIL() << "the internal-reflection term was read under version " << version << " with " << btdf;
    } catch (const common::Error& e) {
      EXPECT_NE(std::string(e.what()).find("internal-reflection"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("material.json"), std::string::npos) << e.what();
    }
  }
}

// The baseline's lobes blend through their slope moments: a lobe blended with itself is itself,
// and azimuths on either side of +-90 degrees average to 90 degrees, not to 0.
TEST(BaselineLobes, BlendThroughSlopeMomentsAndWrapAzimuths) {
  const BaselineLobe lobe{0.3, 0.1, 0.4};
  const BaselineLobe same = BlendBaselineLobes({{lobe, 0.7}, {lobe, 0.3}});
  EXPECT_NEAR(same.alpha_x, 0.3, 1e-9);
  EXPECT_NEAR(same.alpha_y, 0.1, 1e-9);
  EXPECT_NEAR(same.azimuth, 0.4, 1e-9);
  const double near_90 = 88.0 * model::kPi / 180.0;
  const BaselineLobe wrapped = BlendBaselineLobes({{{0.3, 0.1, near_90}, 0.5}, {{0.3, 0.1, -near_90}, 0.5}});
  EXPECT_NEAR(std::abs(wrapped.azimuth), model::kPi / 2, 1e-6);
  EXPECT_NEAR(wrapped.alpha_x, 0.3, 0.01);
  // Affine weights may be negative; the lobe stays a valid GGX.
  const BaselineLobe extrapolated = BlendBaselineLobes({{{0.05, 0.05, 0.0}, 1.5}, {{0.3, 0.3, 0.0}, -0.5}});
  EXPECT_GT(extrapolated.alpha_y, 0.0);
}

}  // namespace
}  // namespace svbtdf::fit

namespace svbtdf::fit {
namespace {

// A blended texel's k_s D is the weighted sum of its representatives' k_s D (what their data
// constrain), not one representative's k_s times another's D: with a sharp representative of
// k_s 20 and a broad one of k_s 1, half and half.
TEST(MaterialBlend, ScaledNdfsBlendAsTheirPredictions) {
  const model::Hemicube grid(32);
  std::vector<TexelFitResult> fits(2);
  const std::array<double, 2> scales = {20.0, 1.0};
  const std::array<double, 2> roughness = {0.1, 0.4};
  std::vector<model::TabulatedNdf> ndfs;
  for (int r = 0; r < 2; ++r) {
    model::TabulatedNdf ndf(grid, model::GgxNdf(roughness[r]));
    ndf.Normalize();
    fits[r].ln_d = ndf.ln_d();
    fits[r].k_s = scales[r];
    fits[r].k_s_rgb = {scales[r], scales[r], scales[r]};
    ndfs.push_back(ndf);
  }
  Clustering clustering;
  clustering.representatives = {0, 1};
  clustering.cluster = {0, 1, 0};
  clustering.weights = {{{{0, 1.0f}}}, {{{1, 1.0f}}}, {{{0, 0.5f}, {1, 0.5f}}}};
  const Material material = AssembleMaterial(3, 1, 1.5, 32, clustering, fits, common::FloatImage(3, 1, 3, 0.0f));
  const MaterialEvaluator evaluator(material);
  const model::TabulatedNdf blended = evaluator.TexelNdf(2, 0);
  const double k_s = material.k_s.at(2, 0, 0);
  EXPECT_NEAR(k_s, 10.5, 1e-5);
  for (double theta : {0.0, 0.1, 0.3, 0.6, 1.0}) {
    const model::Vec3 h(std::sin(theta), 0.0, std::cos(theta));
    const double expected = 0.5 * scales[0] * ndfs[0].D(h) + 0.5 * scales[1] * ndfs[1].D(h);
    EXPECT_NEAR(k_s * blended.D(h) / expected, 1.0, 0.01) << "theta " << theta;
  }
}

}  // namespace
}  // namespace svbtdf::fit
