// DIR/truth/ of a Monte Carlo truth (docs/truth-format.md, "Monte Carlo truth"):
//   material.json  manifest, "ndf": {"kind": "montecarlo"}, the slab materials, the view grid
//   index.exr      1 channel, the material index of each texel (an integer stored as float)
//   rho_d.exr      3 channels, RGB rho_d of each texel
//   slices.exr     width = hemicube cells, height = materials x view nodes (row m * nodes + v),
//                  6 channels A0..A5: RGB cell mean of the tinted rho, then RGB standard error

#include <cmath>
#include <nlohmann/json.hpp>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/json.h"
#include "svbtdf/common/error.h"
#include "svbtdf/simulate/montecarlo_truth.h"

namespace svbtdf::simulate {
namespace fs = std::filesystem;
namespace {

constexpr int kMonteCarloTruthVersion = 2;  // the first truth-format version with this kind

nlohmann::json InterfaceJson(const SlabInterfaceSpec& spec) {
  const model::AnalyticNdfParams& p = spec.params;
  return {{"ndf", spec.ndf}, {"alpha_x", p.alpha_x}, {"alpha_y", p.alpha_y}, {"theta_x", p.theta_x},
          {"theta_y", p.theta_y}, {"theta_z", p.theta_z}, {"kappa", p.kappa},
          {"mean", {p.mean.x(), p.mean.y(), p.mean.z()}}};
}

SlabInterfaceSpec InterfaceFromJson(const nlohmann::json& in) {
  SlabInterfaceSpec spec;
  spec.ndf = in.at("ndf").get<std::string>();
  model::AnalyticNdfParams& p = spec.params;
  p.alpha_x = in.at("alpha_x").get<double>();
  p.alpha_y = in.at("alpha_y").get<double>();
  p.theta_x = in.at("theta_x").get<double>();
  p.theta_y = in.at("theta_y").get<double>();
  p.theta_z = in.at("theta_z").get<double>();
  p.kappa = in.at("kappa").get<double>();
  const auto mean = in.at("mean").get<std::array<double, 3>>();
  p.mean = model::Vec3(mean[0], mean[1], mean[2]);
  model::MakeAnalyticNdf(spec.ndf, p);  // rejects an unknown NDF or bad parameters now, not when rendering
  return spec;
}

nlohmann::json MaterialJson(const SlabMaterial& m) {
  return {{"label", m.label}, {"entry", InterfaceJson(m.entry)}, {"exit", InterfaceJson(m.exit)},
          {"optical_depth", m.optical_depth}, {"tint", m.tint}, {"rho_d", m.rho_d}};
}

SlabMaterial MaterialFromJson(const nlohmann::json& in) {
  SlabMaterial m;
  m.label = in.at("label").get<std::string>();
  m.entry = InterfaceFromJson(in.at("entry"));
  m.exit = InterfaceFromJson(in.at("exit"));
  m.optical_depth = in.at("optical_depth").get<double>();
  m.tint = in.at("tint").get<model::Rgb>();
  m.rho_d = in.at("rho_d").get<model::Rgb>();
  return m;
}

nlohmann::json Manifest(const MonteCarloTruth& truth) {
  nlohmann::json materials = nlohmann::json::array();
  for (const SlabMaterial& m : truth.materials()) materials.push_back(MaterialJson(m));
  const ViewGrid& v = truth.views();
  return {
      {"format", "svbtdf-truth-material"},
      {"version", kMonteCarloTruthVersion},
      {"eta", truth.eta()},
      {"width", truth.texels_x()},
      {"height", truth.texels_y()},
      {"ndf", {{"kind", "montecarlo"}}},
      {"materials", materials},
      {"view_grid", {{"nx", v.nx}, {"ny", v.ny}, {"ox", {v.x0, v.x1}}, {"oy", {v.y0, v.y1}}}},
      {"hemicube_resolution", truth.hemicube().resolution()},
      {"monte_carlo", {{"paths_per_slice", truth.precision.paths},
                       {"max_interactions", truth.precision.max_interactions},
                       {"seed", truth.seed},
                       {"dominant_relative_error_max", std::isfinite(truth.dominant_relative_error)
                                                           ? nlohmann::json(truth.dominant_relative_error)
                                                           : nlohmann::json(nullptr)}}},
      {"maps", {{"index", "index.exr"}, {"rho_d", "rho_d.exr"}, {"slices", "slices.exr"}}},
      {"btdf", "R(x,i,o)[c] = sum_v w_v(o) sum_cell w_cell(FlipZ(i)) slices[m(x)][v][cell][c] + rho_d(x)[c]"},
  };
}

// The slice tables as one image: a row per (material, view node), a column per cell.
common::FloatImage SlicesImage(const MonteCarloTruth& truth) {
  const int cells = truth.hemicube().num_cells(), nodes = truth.views().num_nodes();
  const int materials = static_cast<int>(truth.materials().size());
  common::FloatImage image(cells, materials * nodes, 6);
  for (int m = 0; m < materials; ++m) {
    for (int v = 0; v < nodes; ++v) {
      for (int cell = 0; cell < cells; ++cell) {
        const model::Rgb value = truth.SliceValue(m, v, cell), error = truth.SliceError(m, v, cell);
        for (int c = 0; c < 3; ++c) {
          image.at(cell, m * nodes + v, c) = static_cast<float>(value[c]);
          image.at(cell, m * nodes + v, 3 + c) = static_cast<float>(error[c]);
        }
      }
    }
  }
  return image;
}

common::FloatImage ReadMap(const fs::path& path, int width, int height, int channels) {
  common::FloatImage image = common::ReadFloatImage(path);
  common::RequireFinite(image, path.string());
  if (image.width != width || image.height != height || image.channels != channels) {
    common::ThrowFormatError(path.string(), "is " + std::to_string(image.width) + "x" + std::to_string(image.height) + "x" +
                                        std::to_string(image.channels) + ", expected " + std::to_string(width) + "x" +
                                        std::to_string(height) + "x" + std::to_string(channels));
  }
  return image;
}

std::vector<int> IndexFromImage(const common::FloatImage& image, int materials, const fs::path& path) {
  std::vector<int> map(image.pixels.size());
  for (size_t t = 0; t < map.size(); ++t) {
    const float value = image.pixels[t];
    if (value != std::round(value) || value < 0 || value >= materials) {
      common::ThrowFormatError(path.string(), "texel " + std::to_string(t) + " holds " + std::to_string(value) +
                                          ", not a material index in [0, " + std::to_string(materials) + ")");
    }
    map[t] = static_cast<int>(value);
  }
  return map;
}

void SplitSlices(const common::FloatImage& image, std::vector<float>* values, std::vector<float>* errors) {
  const size_t entries = static_cast<size_t>(image.width) * image.height;
  values->resize(entries * 3);
  errors->resize(entries * 3);
  for (size_t e = 0; e < entries; ++e) {
    for (int c = 0; c < 3; ++c) {
      (*values)[e * 3 + c] = image.pixels[e * 6 + c];
      (*errors)[e * 3 + c] = image.pixels[e * 6 + 3 + c];
    }
  }
}

nlohmann::json ReadManifest(const fs::path& path) {
  try {
    nlohmann::json manifest = common::ReadJsonFile(path);
    if (manifest.at("format") != "svbtdf-truth-material") common::ThrowFormatError(path.string(), "is not a truth material");
    return manifest;
  } catch (const nlohmann::json::exception& e) {
    common::ThrowFormatError(path.string(), std::string("is malformed: ") + e.what());
  }
}

}  // namespace

std::string ReadTruthKind(const fs::path& folder) {
  const fs::path path = folder / "material.json";
  const nlohmann::json manifest = ReadManifest(path);
  try {
    return manifest.at("ndf").at("kind").get<std::string>();
  } catch (const nlohmann::json::exception& e) {
    common::ThrowFormatError(path.string(), std::string("is malformed: ") + e.what());
  }
}

void WriteMonteCarloTruth(const fs::path& folder, const MonteCarloTruth& truth) {
  const int w = truth.texels_x(), h = truth.texels_y();
  common::FloatImage index(w, h, 1), rho_d(w, h, 3);
  for (int t = 0; t < truth.num_texels(); ++t) {
    index.pixels[t] = static_cast<float>(truth.material_of(t));
    for (int c = 0; c < 3; ++c) rho_d.pixels[t * 3 + c] = static_cast<float>(truth.rho_d(t)[c]);
  }
  // The maps may be rewritten by a resumed run; the manifest, written last, marks the truth
  // complete and is never overwritten.
  common::WriteFloatImage(folder / "index.exr", index, /*half_precision=*/false, /*overwrite=*/true);
  common::WriteFloatImage(folder / "rho_d.exr", rho_d, false, true);
  common::WriteFloatImage(folder / "slices.exr", SlicesImage(truth), false, true);
  common::WriteTextAtomically(folder / "material.json", Manifest(truth).dump(2) + "\n", /*overwrite=*/false);
}

MonteCarloTruth ReadMonteCarloTruth(const fs::path& folder) {
  const fs::path path = folder / "material.json";
  const nlohmann::json manifest = ReadManifest(path);
  try {
    if (manifest.at("ndf").at("kind") != "montecarlo") common::ThrowFormatError(path.string(), "is not a Monte Carlo truth");
    if (common::IntegerAt(manifest, "version", path.string()) != kMonteCarloTruthVersion) {
      common::ThrowFormatError(path.string(), "has version " + manifest.at("version").dump() + ", this build reads version " +
                                          std::to_string(kMonteCarloTruthVersion));
    }
    std::vector<SlabMaterial> materials;
    for (const nlohmann::json& m : manifest.at("materials")) materials.push_back(MaterialFromJson(m));
    ViewGrid views;
    const nlohmann::json& grid = manifest.at("view_grid");
    views.nx = common::IntegerAt(grid, "nx", path.string());
    views.ny = common::IntegerAt(grid, "ny", path.string());
    views.x0 = grid.at("ox").at(0).get<double>();
    views.x1 = grid.at("ox").at(1).get<double>();
    views.y0 = grid.at("oy").at(0).get<double>();
    views.y1 = grid.at("oy").at(1).get<double>();
    const int w = common::IntegerAt(manifest, "width", path.string());
    const int h = common::IntegerAt(manifest, "height", path.string());
    const int resolution = common::IntegerAt(manifest, "hemicube_resolution", path.string());
    if (w < 1 || h < 1 || materials.empty() || views.nx < 2 || views.ny < 2 || resolution < 4 || resolution % 2) {
      common::ThrowFormatError(path.string(), "has an empty texel grid, no materials, a view grid under 2x2 or a bad "
                                      "hemicube resolution");
    }
    const int materials_count = static_cast<int>(materials.size());
    const common::FloatImage index_image = ReadMap(folder / "index.exr", w, h, 1);
    const common::FloatImage rho_d_image = ReadMap(folder / "rho_d.exr", w, h, 3);
    const common::FloatImage slices = ReadMap(folder / "slices.exr", model::Hemicube(resolution).num_cells(),
                                      materials_count * views.num_nodes(), 6);
    std::vector<model::Rgb> rho_d(static_cast<size_t>(w) * h);
    for (size_t t = 0; t < rho_d.size(); ++t) {
      rho_d[t] = {rho_d_image.pixels[t * 3], rho_d_image.pixels[t * 3 + 1], rho_d_image.pixels[t * 3 + 2]};
    }
    std::vector<float> values, errors;
    SplitSlices(slices, &values, &errors);
    try {
      MonteCarloTruth truth(w, h, manifest.at("eta").get<double>(), std::move(materials),
                            IndexFromImage(index_image, materials_count, folder / "index.exr"), std::move(rho_d),
                            views, resolution, std::move(values), std::move(errors));
      const nlohmann::json& mc = manifest.at("monte_carlo");
      truth.precision = {resolution, common::IntegerAt<int64_t>(mc, "paths_per_slice", path.string()),
                         common::IntegerAt(mc, "max_interactions", path.string())};
      truth.seed = common::IntegerAt<uint64_t>(mc, "seed", path.string());
      const nlohmann::json& error = mc.at("dominant_relative_error_max");
      truth.dominant_relative_error = error.is_null() ? std::nan("") : error.get<double>();
      return truth;
    } catch (const common::Error& e) {
      if (e.kind() != common::ErrorKind::kInvalidInput) throw;
      common::ThrowFormatError(folder.string(), "holds an inconsistent Monte Carlo truth: " + e.problem());
    }
  } catch (const nlohmann::json::exception& e) {
    common::ThrowFormatError(path.string(), std::string("is malformed: ") + e.what());
  } catch (const common::Error& e) {
    // An NDF the factory rejects is bad input from this file.
    if (e.kind() != common::ErrorKind::kInvalidInput) throw;
    common::ThrowFormatError(path.string(), "names an invalid slab interface: " + e.problem());
  }
}

}  // namespace svbtdf::simulate
