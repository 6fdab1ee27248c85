// The analytic ground-truth material: material.json and its EXR maps (docs/truth-format.md).

#include <nlohmann/json.hpp>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/json.h"
#include "svbtdf/common/error.h"
#include "svbtdf/model/ndf_factory.h"
#include "svbtdf/simulate/truth_io.h"

namespace svbtdf::simulate {
namespace fs = std::filesystem;

void WriteMaterialTruth(const fs::path& folder, const TruthMaterial& material) {
  const int w = material.texels_x(), h = material.texels_y();
  common::FloatImage ndf(w, h, 5), alpha(w, h, 1), shadowing(w, h, 1), k_s(w, h, 3), rho_d(w, h, 3);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const TruthTexel& t = material.texel(x, y);
      const double ndf_params[5] = {t.ndf.alpha_x, t.ndf.alpha_y, t.ndf.theta_x, t.ndf.theta_y, t.ndf.theta_z};
      for (int c = 0; c < 5; ++c) ndf.at(x, y, c) = static_cast<float>(ndf_params[c]);
      alpha.at(x, y) = static_cast<float>(t.alpha);
      shadowing.at(x, y) = static_cast<float>(t.shadowing_roughness);
      for (int c = 0; c < 3; ++c) {
        k_s.at(x, y, c) = static_cast<float>(t.k_s[c]);
        rho_d.at(x, y, c) = static_cast<float>(t.rho_d[c]);
      }
    }
  }
  // material.json, written last and never overwritten, says the truth is whole; maps without it
  // are what an interrupted run left, and are written again.
  common::WriteFloatImage(folder / "ndf_params.exr", ndf, /*half_precision=*/false, /*overwrite=*/true);
  common::WriteFloatImage(folder / "alpha.exr", alpha, false, true);
  common::WriteFloatImage(folder / "shadowing_roughness.exr", shadowing, false, true);
  common::WriteFloatImage(folder / "k_s.exr", k_s, false, true);
  common::WriteFloatImage(folder / "rho_d.exr", rho_d, false, true);
  const nlohmann::json manifest = {
      {"format", "svbtdf-truth-material"},
      {"version", kTruthFormatVersion},
      {"eta", material.eta()},
      {"width", w},
      {"height", h},
      {"ndf", {{"kind", "analytic"}, {"name", material.ndf_name()}, {"map", "ndf_params.exr"},
               {"channels", {"alpha_x", "alpha_y", "theta_x", "theta_y", "theta_z"}}}},
      {"maps", {{"alpha", "alpha.exr"}, {"shadowing_roughness", "shadowing_roughness.exr"},
                {"k_s", "k_s.exr"}, {"rho_d", "rho_d.exr"}}},
      {"shadowing", "smith-ggx; 0 = none"},
  };
  common::WriteTextAtomically(folder / "material.json", manifest.dump(2) + "\n", false);
}


MaterialTruth ReadMaterialTruth(const fs::path& folder) {
  const fs::path manifest_path = folder / "material.json";
  MaterialTruth truth;
  try {
    const nlohmann::json manifest = common::ReadJsonFile(manifest_path);
    if (manifest.at("format") != "svbtdf-truth-material") common::ThrowFormatError(manifest_path.string(), "is not a truth material");
    if (manifest.at("ndf").at("kind") != "analytic") {
      common::ThrowFormatError(manifest_path.string(), "is not an analytic truth (see its ndf.kind)");
    }
    truth.eta = manifest.at("eta").get<double>();
    truth.ndf_name = manifest.at("ndf").at("name").get<std::string>();
  } catch (const nlohmann::json::exception& e) {
    common::ThrowFormatError(manifest_path.string(), std::string("is malformed: ") + e.what());
  }
  const auto read = [&](const char* file, int channels) {
    common::FloatImage image = common::ReadFloatImage(folder / file);
    common::RequireFinite(image, (folder / file).string());
    if (image.channels != channels) common::ThrowFormatError((folder / file).string(), "has the wrong number of channels");
    return image;
  };
  truth.ndf_params = read("ndf_params.exr", 5);
  truth.alpha = read("alpha.exr", 1);
  truth.shadowing_roughness = read("shadowing_roughness.exr", 1);
  truth.k_s = read("k_s.exr", 3);
  truth.rho_d = read("rho_d.exr", 3);
  for (const common::FloatImage* image : {&truth.ndf_params, &truth.shadowing_roughness, &truth.k_s, &truth.rho_d}) {
    if (image->width != truth.alpha.width || image->height != truth.alpha.height) {
      common::ThrowFormatError(folder.string(), "holds maps of different sizes");
    }
  }
  return truth;
}

model::DualMicrofacetParams MaterialTruth::Params(int x, int y) const {
  model::DualMicrofacetParams p;
  p.eta = eta;
  p.alpha = alpha.at(x, y);
  const double roughness = shadowing_roughness.at(x, y);
  p.shadowing = roughness > 0 ? model::SmithShadowing::Ggx(roughness) : model::SmithShadowing::None();
  for (int c = 0; c < 3; ++c) {
    p.k_s[c] = k_s.at(x, y, c);
    p.rho_d[c] = rho_d.at(x, y, c);
  }
  return p;
}

std::unique_ptr<model::Ndf> MaterialTruth::TexelNdf(int x, int y) const {
  model::AnalyticNdfParams p;
  p.alpha_x = ndf_params.at(x, y, 0);
  p.alpha_y = ndf_params.at(x, y, 1);
  p.theta_x = ndf_params.at(x, y, 2);
  p.theta_y = ndf_params.at(x, y, 3);
  p.theta_z = ndf_params.at(x, y, 4);
  return model::MakeAnalyticNdf(ndf_name, p);
}

TruthMaterial MaterialTruth::ToTruthMaterial() const {
  std::vector<TruthTexel> texels;
  texels.reserve(static_cast<size_t>(width()) * height());
  for (int y = 0; y < height(); ++y) {
    for (int x = 0; x < width(); ++x) {
      const model::DualMicrofacetParams p = Params(x, y);
      TruthTexel t;
      t.ndf = {ndf_params.at(x, y, 0), ndf_params.at(x, y, 1), ndf_params.at(x, y, 2), ndf_params.at(x, y, 3),
               ndf_params.at(x, y, 4)};
      t.alpha = p.alpha;
      t.shadowing_roughness = shadowing_roughness.at(x, y);
      t.k_s = p.k_s;
      t.rho_d = p.rho_d;
      texels.push_back(t);
    }
  }
  return TruthMaterial(width(), height(), eta, ndf_name, std::move(texels));
}

}  // namespace svbtdf::simulate
