#include "svbtdf/fit/material.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/json.h"
#include "svbtdf/common/error.h"

namespace svbtdf::fit {
namespace fs = std::filesystem;
namespace {

// The map files and the channel count each must have.
struct MapSpec {
  const char* key;
  const char* file;
  common::FloatImage Material::*image;
  int channels;  // 0: any (the weights' K)
};

const MapSpec kMaps[] = {
    {"alpha", "alpha.exr", &Material::alpha, 1},
    {"shadowing_roughness", "shadowing_roughness.exr", &Material::shadowing_roughness, 1},
    {"k_s", "k_s.exr", &Material::k_s, 3},
    {"rho_d", "rho_d.exr", &Material::rho_d, 3},
    {"residual", "residual.exr", &Material::residual, 1},
    {"cluster", "cluster.exr", &Material::cluster, 1},
    {"weight_index", "weight_index.exr", &Material::weight_index, 0},
    {"weight_value", "weight_value.exr", &Material::weight_value, 0},
};

// The baseline's lobe maps (walter-ggx materials only).
const MapSpec kBaselineMaps[] = {
    {"baseline_alpha_x", "baseline_alpha_x.exr", &Material::baseline_alpha_x, 1},
    {"baseline_alpha_y", "baseline_alpha_y.exr", &Material::baseline_alpha_y, 1},
    {"baseline_azimuth", "baseline_azimuth.exr", &Material::baseline_azimuth, 1},
};

// The slab's interface maps (slab materials only, version 5).
const MapSpec kSlabMaps[] = {
    {"slab_entry_alpha_x", "slab_entry_alpha_x.exr", &Material::slab_entry_alpha_x, 1},
    {"slab_entry_alpha_y", "slab_entry_alpha_y.exr", &Material::slab_entry_alpha_y, 1},
    {"slab_exit_alpha_x", "slab_exit_alpha_x.exr", &Material::slab_exit_alpha_x, 1},
    {"slab_exit_alpha_y", "slab_exit_alpha_y.exr", &Material::slab_exit_alpha_y, 1},
    {"slab_entry_azimuth", "slab_entry_azimuth.exr", &Material::slab_entry_azimuth, 1},
    {"slab_exit_azimuth", "slab_exit_azimuth.exr", &Material::slab_exit_azimuth, 1},
    {"slab_entry_roughness_se", "slab_entry_roughness_se.exr", &Material::slab_entry_roughness_se, 1},
    {"slab_exit_roughness_se", "slab_exit_roughness_se.exr", &Material::slab_exit_roughness_se, 1},
    {"slab_internal_reflection", "slab_internal_reflection.exr", &Material::slab_internal_reflection, 1},
};

// The longer internal paths' weight (slab materials, version 6; 0 in a version 5 slab).
const MapSpec kSlabLongerPathsMap = {"slab_longer_paths", "slab_longer_paths.exr", &Material::slab_longer_paths, 1};

// The standard errors (version 3; docs/fitting.md, "Uncertainty").
const MapSpec kUncertaintyMaps[] = {
    {"alpha_se", "alpha_se.exr", &Material::alpha_se, 1},
    {"k_s_se", "k_s_se.exr", &Material::k_s_se, 3},
    {"rho_d_se", "rho_d_se.exr", &Material::rho_d_se, 3},
    {"shadowing_roughness_se", "shadowing_roughness_se.exr", &Material::shadowing_roughness_se, 1},
    {"ndf_width", "ndf_width.exr", &Material::ndf_width, 1},
    {"ndf_width_se", "ndf_width_se.exr", &Material::ndf_width_se, 1},
    {"prediction_se", "prediction_se.exr", &Material::prediction_se, 1},
};

// The maps of a material of `version` (the writer's: kMaterialFormatVersion).
std::vector<MapSpec> MapsOf(MaterialModel model, bool uncertainty, int version = kMaterialFormatVersion) {
  std::vector<MapSpec> maps(std::begin(kMaps), std::end(kMaps));
  if (model == MaterialModel::kWalterGgx) maps.insert(maps.end(), std::begin(kBaselineMaps), std::end(kBaselineMaps));
  if (model == MaterialModel::kSlab) maps.insert(maps.end(), std::begin(kSlabMaps), std::end(kSlabMaps));
  if (model == MaterialModel::kSlab && version >= 6) maps.push_back(kSlabLongerPathsMap);
  if (uncertainty) maps.insert(maps.end(), std::begin(kUncertaintyMaps), std::end(kUncertaintyMaps));
  return maps;
}

// The manifest's description of the BTDF (for people; readers use "btdf").
const char* ModelFormula(MaterialModel model) {
  switch (model) {
    case MaterialModel::kWalterGgx:
      return "walter-ggx: R = k_s f_Walter(GGX(baseline_alpha_x, baseline_alpha_y) rotated by baseline_azimuth; i, o, "
             "1, eta) + rho_d";
    case MaterialModel::kSlab:
      return "slab: R = k_s (rho_TT + slab_internal_reflection IR + slab_longer_paths IR[widened by sqrt(2)])(entry "
             "GGX(slab_entry_alpha_x, slab_entry_alpha_y) turned by slab_entry_azimuth, exit likewise; i, o, eta) + rho_d "
             "(docs/model.md, \"Two rough interfaces\")";
    case MaterialModel::kDualMicrofacet:
      break;
  }
  return "dual-microfacet: R = k_s exp(alpha ln rho_T + (1 - alpha) ln rho_B) + rho_d";
}

int MinimumVersion(const Material& m) {
  if (m.model == MaterialModel::kSlab) return 6;
  if (m.internal_reflection) return 4;
  if (m.has_uncertainty()) return 3;
  return m.model == MaterialModel::kWalterGgx ? 2 : 1;
}

MaterialModel ParseModel(const std::string& name, const std::string& source) {
  if (name == "dual-microfacet") return MaterialModel::kDualMicrofacet;
  if (name == "walter-ggx") return MaterialModel::kWalterGgx;
  if (name == "slab") return MaterialModel::kSlab;
  common::ThrowFormatError(source, "has an unknown btdf '" + name + "' (expected dual-microfacet, walter-ggx or slab)");
}

// "WxH" or "WxHxC"; built with += because GCC 12 misreads a long chain of temporaries as an overflow.
std::string ShapeText(int width, int height, int channels) {
  std::string text = std::to_string(width);
  text += 'x';
  text += std::to_string(height);
  if (channels > 0) {
    text += 'x';
    text += std::to_string(channels);
  }
  return text;
}

void CheckShape(const common::FloatImage& image, int width, int height, int channels, const std::string& source) {
  if (image.width != width || image.height != height || (channels > 0 && image.channels != channels)) {
    common::ThrowFormatError(source, "is " + ShapeText(image.width, image.height, image.channels) + ", expected " +
                                         ShapeText(width, height, channels));
  }
}

// The standard error of a texel's blended shadowing roughness sum_j w_j r_j: the
// representatives' own errors propagated, sum_j w_j^2 se_j^2, plus the spread of their values
// about the blend, sum_j |w_j| (r_j - r)^2 / sum_j |w_j|, which stands for what interpolating
// between texels that differ cannot know. -1 when a representative's is not known.
double BlendedStandardError(const std::vector<std::pair<int, float>>& terms, const std::vector<TexelFitResult>& fits) {
  double blend = 0, total = 0, variance = 0;
  for (const auto& [rep, w] : terms) {
    if (!(fits[rep].shadowing_roughness_se >= 0)) return -1.0;
    blend += w * fits[rep].shadowing_roughness;
    total += std::abs(w);
    variance += model::Square(w * fits[rep].shadowing_roughness_se);
  }
  if (!(total > 0)) return -1.0;
  for (const auto& [rep, w] : terms) variance += std::abs(w) * model::Square(fits[rep].shadowing_roughness - blend) / total;
  return std::sqrt(variance);
}

}  // namespace

Material AssembleMaterial(int width, int height, double eta, int ndf_resolution, const Clustering& clustering,
                          const std::vector<TexelFitResult>& representative_fits, const common::FloatImage& rho_d) {
  const size_t texels = static_cast<size_t>(width) * height;
  if (clustering.weights.size() != texels || representative_fits.size() != clustering.representatives.size()) {
    common::ThrowInvalidInput("material", "the clustering, the fits and the material size disagree");
  }
  CheckShape(rho_d, width, height, 3, "rho_d map");
  Material m;
  m.width = width;
  m.height = height;
  m.eta = eta;
  m.ndf_resolution = ndf_resolution;
  m.representative_texels = clustering.representatives;
  for (const TexelFitResult& fit : representative_fits) m.representative_ln_d.push_back(fit.ln_d);
  size_t max_terms = 1;
  for (const AffineWeights& w : clustering.weights) max_terms = std::max(max_terms, w.terms.size());
  const int k = static_cast<int>(max_terms);
  m.alpha = common::FloatImage(width, height, 1);
  m.shadowing_roughness = common::FloatImage(width, height, 1);
  m.k_s = common::FloatImage(width, height, 3);
  m.rho_d = rho_d;
  m.residual = common::FloatImage(width, height, 1, -1.0f);
  m.cluster = common::FloatImage(width, height, 1);
  m.weight_index = common::FloatImage(width, height, k);
  m.weight_value = common::FloatImage(width, height, k);
  for (size_t r = 0; r < clustering.representatives.size(); ++r) {
    const int64_t t = clustering.representatives[r];
    m.residual.pixels[t] = static_cast<float>(representative_fits[r].relative_rmse);
  }
  // The standard errors (docs/fitting.md, "Uncertainty"). alpha, k_s, rho_d and the prediction's
  // are the refinement's (-1 until it runs); the shadowing roughness and the NDF width are the
  // representatives', blended below.
  m.alpha_se = common::FloatImage(width, height, 1, -1.0f);
  m.k_s_se = common::FloatImage(width, height, 3, -1.0f);
  m.rho_d_se = common::FloatImage(width, height, 3, -1.0f);
  m.shadowing_roughness_se = common::FloatImage(width, height, 1, -1.0f);
  m.ndf_width = common::FloatImage(width, height, 1, -1.0f);
  m.ndf_width_se = common::FloatImage(width, height, 1, -1.0f);
  m.prediction_se = common::FloatImage(width, height, 1, -1.0f);
  for (size_t r = 0; r < clustering.representatives.size(); ++r) {
    const int64_t t = clustering.representatives[r];
    m.ndf_width.pixels[t] = static_cast<float>(representative_fits[r].ndf_width);
    m.ndf_width_se.pixels[t] = static_cast<float>(representative_fits[r].ndf_width_se);
  }
  for (size_t t = 0; t < texels; ++t) {
    const int x = static_cast<int>(t % width), y = static_cast<int>(t / width);
    double alpha = 0, shadowing = 0;
    std::array<double, 3> k_s = {0, 0, 0};
    const auto& terms = clustering.weights[t].terms;
    for (size_t j = 0; j < terms.size(); ++j) {
      const auto& [rep, w] = terms[j];
      const TexelFitResult& fit = representative_fits[rep];
      alpha += w * fit.alpha;
      shadowing += w * fit.shadowing_roughness;
      for (int c = 0; c < 3; ++c) k_s[c] += w * fit.k_s_rgb[c];
      m.weight_index.at(x, y, static_cast<int>(j)) = static_cast<float>(rep);
      m.weight_value.at(x, y, static_cast<int>(j)) = w;
    }
    m.alpha.at(x, y) = static_cast<float>(std::clamp(alpha, 0.0, 1.0));
    m.shadowing_roughness.at(x, y) = static_cast<float>(std::max(0.0, shadowing));
    m.shadowing_roughness_se.at(x, y) = static_cast<float>(BlendedStandardError(terms, representative_fits));
    // alpha's and k_s's share of what the data cannot tell apart (the representatives' profiles
    // over alpha, TexelFitResult): their variances averaged with the weights' sizes. The
    // refinement adds its own statistical error to these.
    double weight_sum = 0, alpha_variance = 0, k_s_variance = 0;
    bool known = !terms.empty();
    for (const auto& [rep, w] : terms) {
      const TexelFitResult& fit = representative_fits[rep];
      known = known && fit.alpha_profile_se >= 0 && fit.k_s_profile_relative_se >= 0;
      weight_sum += std::abs(w);
      alpha_variance += std::abs(w) * model::Square(fit.alpha_profile_se);
      k_s_variance += std::abs(w) * model::Square(fit.k_s_profile_relative_se);
    }
    if (known && weight_sum > 0) {
      m.alpha_se.at(x, y) = static_cast<float>(std::sqrt(alpha_variance / weight_sum));
      for (int c = 0; c < 3; ++c) {
        m.k_s_se.at(x, y, c) = static_cast<float>(std::max(0.0, k_s[c]) * std::sqrt(k_s_variance / weight_sum));
      }
    }
    for (int c = 0; c < 3; ++c) m.k_s.at(x, y, c) = static_cast<float>(std::max(0.0, k_s[c]));
    m.cluster.at(x, y) = static_cast<float>(clustering.cluster[t]);
  }
  return m;
}

const char* MaterialModelName(MaterialModel model) {
  switch (model) {
    case MaterialModel::kWalterGgx:
      return "walter-ggx";
    case MaterialModel::kSlab:
      return "slab";
    case MaterialModel::kDualMicrofacet:
      break;
  }
  return "dual-microfacet";
}

Material AssembleBaselineMaterial(int width, int height, double eta, int ndf_resolution, const Clustering& clustering,
                                  const std::vector<BaselineFitResult>& representative_fits, const common::FloatImage& rho_d) {
  // The shared maps (k_s, residual, weights, NDF tables of the lobes) through the dual path.
  const model::Hemicube grid(ndf_resolution);
  std::vector<TexelFitResult> as_dual(representative_fits.size());
  for (size_t r = 0; r < representative_fits.size(); ++r) {
    const BaselineFitResult& b = representative_fits[r];
    as_dual[r].alpha = 0.0;
    as_dual[r].shadowing_roughness = 0.0;
    as_dual[r].k_s = b.k_s;
    as_dual[r].k_s_rgb = b.k_s_rgb;
    as_dual[r].ln_d = BaselineLnD(grid, b.lobe());
    as_dual[r].relative_rmse = b.relative_rmse;
  }
  // Every texel takes its cluster's representative whole. Affine blends of the baseline's fits
  // are unsafe: where it cannot reach the measured lobe (it refracts once, so its lobe is
  // displaced) its best log fit can be a near-delta lobe with a huge scale, and a texel blending
  // such a scale with its neighbours' wide lobes was off by a factor of 1000s (docs/fitting.md).
  Clustering by_cluster = clustering;
  for (size_t t = 0; t < by_cluster.weights.size(); ++t) by_cluster.weights[t].terms = {{by_cluster.cluster[t], 1.0f}};
  Material m = AssembleMaterial(width, height, eta, ndf_resolution, by_cluster, as_dual, rho_d);
  m.model = MaterialModel::kWalterGgx;
  // The baseline carries no standard errors (they are the dual-microfacet fit's).
  for (common::FloatImage* map : {&m.alpha_se, &m.k_s_se, &m.rho_d_se, &m.shadowing_roughness_se, &m.ndf_width,
                                  &m.ndf_width_se, &m.prediction_se}) {
    *map = common::FloatImage();
  }
  m.baseline_alpha_x = common::FloatImage(width, height, 1);
  m.baseline_alpha_y = common::FloatImage(width, height, 1);
  m.baseline_azimuth = common::FloatImage(width, height, 1);
  for (int64_t t = 0; t < static_cast<int64_t>(width) * height; ++t) {
    std::vector<std::pair<BaselineLobe, double>> weighted;
    for (const auto& [rep, w] : by_cluster.weights[t].terms) weighted.emplace_back(representative_fits[rep].lobe(), w);
    const BaselineLobe lobe = BlendBaselineLobes(weighted);
    m.baseline_alpha_x.pixels[t] = static_cast<float>(lobe.alpha_x);
    m.baseline_alpha_y.pixels[t] = static_cast<float>(lobe.alpha_y);
    m.baseline_azimuth.pixels[t] = static_cast<float>(lobe.azimuth);
  }
  return m;
}

Material AssembleSlabMaterial(int width, int height, double eta, int ndf_resolution, const Clustering& clustering,
                              const std::vector<SlabFitResult>& representative_fits, const common::FloatImage& rho_d) {
  // The shared maps through the baseline's path, with the exit's GGX as each NDF table.
  std::vector<BaselineFitResult> as_baseline(representative_fits.size());
  for (size_t r = 0; r < representative_fits.size(); ++r) {
    const SlabFitResult& f = representative_fits[r];
    as_baseline[r].alpha_x = f.interfaces.exit.alpha_x;
    as_baseline[r].alpha_y = f.interfaces.exit.alpha_y;
    as_baseline[r].azimuth = f.interfaces.exit.azimuth;
    as_baseline[r].k_s = f.k_s;
    as_baseline[r].k_s_rgb = f.k_s_rgb;
    as_baseline[r].relative_rmse = f.relative_rmse;
  }
  Material m = AssembleBaselineMaterial(width, height, eta, ndf_resolution, clustering, as_baseline, rho_d);
  m.model = MaterialModel::kSlab;
  for (common::FloatImage* map : {&m.baseline_alpha_x, &m.baseline_alpha_y, &m.baseline_azimuth}) *map = common::FloatImage();
  for (const MapSpec& spec : kSlabMaps) m.*spec.image = common::FloatImage(width, height, 1);
  m.slab_longer_paths = common::FloatImage(width, height, 1);
  // Every texel takes its cluster's representative whole (AssembleBaselineMaterial's weights).
  for (int64_t t = 0; t < static_cast<int64_t>(width) * height; ++t) {
    const SlabFitResult& f = representative_fits.at(clustering.cluster[t]);
    const SlabSide& entry = f.interfaces.entry;
    const SlabSide& exit = f.interfaces.exit;
    m.slab_entry_alpha_x.pixels[t] = static_cast<float>(entry.alpha_x);
    m.slab_entry_alpha_y.pixels[t] = static_cast<float>(entry.alpha_y);
    m.slab_entry_azimuth.pixels[t] = static_cast<float>(entry.azimuth);
    m.slab_exit_alpha_x.pixels[t] = static_cast<float>(exit.alpha_x);
    m.slab_exit_alpha_y.pixels[t] = static_cast<float>(exit.alpha_y);
    m.slab_exit_azimuth.pixels[t] = static_cast<float>(exit.azimuth);
    m.slab_entry_roughness_se.pixels[t] = static_cast<float>(f.entry_roughness_se);
    m.slab_exit_roughness_se.pixels[t] = static_cast<float>(f.exit_roughness_se);
    m.slab_internal_reflection.pixels[t] = static_cast<float>(f.interfaces.internal_reflection);
    m.slab_longer_paths.pixels[t] = static_cast<float>(f.interfaces.longer_paths);
  }
  return m;
}

void WriteMaterial(const fs::path& folder, const Material& m) {
  if (fs::exists(folder) && (!fs::is_directory(folder) || !fs::is_empty(folder))) {
    common::ThrowInvalidInput(folder.string(), "exists and is not empty; a material is never overwritten",
                      "choose a new --out folder");
  }
  std::error_code error;
  fs::create_directories(folder, error);
  if (error) common::ThrowIoError(folder.string(), "cannot create: " + error.message());
  const model::Hemicube grid(m.ndf_resolution);
  if (m.internal_reflection && m.model != MaterialModel::kDualMicrofacet) {
    common::ThrowInvalidInput("material", "the internal-reflection term belongs to the dual-microfacet model only");
  }
  if (m.representative_ln_d.size() != m.representative_texels.size() || m.representative_texels.empty()) {
    common::ThrowInvalidInput("material", "needs one ln D table per representative, and at least one representative");
  }
  common::FloatImage tables(grid.num_cells(), static_cast<int>(m.representative_ln_d.size()), 1);
  for (size_t r = 0; r < m.representative_ln_d.size(); ++r) {
    if (static_cast<int>(m.representative_ln_d[r].size()) != grid.num_cells()) {
      common::ThrowInvalidInput("material", "representative " + std::to_string(r) + " has a table of the wrong size");
    }
    for (int c = 0; c < grid.num_cells(); ++c) tables.at(c, static_cast<int>(r)) = static_cast<float>(m.representative_ln_d[r][c]);
  }
  common::WriteFloatImage(folder / "ndf_ln_d.exr", tables, /*half_precision=*/false, false);
  nlohmann::json maps = nlohmann::json::object();
  for (const MapSpec& spec : MapsOf(m.model, m.has_uncertainty())) {
    CheckShape(m.*spec.image, m.width, m.height, spec.channels, std::string("material map ") + spec.key);
    // Parameters in full float: k_s and rho_d would survive half, indices would not.
    common::WriteFloatImage(folder / spec.file, m.*spec.image, /*half_precision=*/false, false);
    maps[spec.key] = spec.file;
  }
  nlohmann::json manifest = {
      {"format", "svbtdf-material"},
      // Version 1 readers would evaluate a baseline as a dual-microfacet material: only it needs 2.
      // The standard errors need 3 (a version 2 reader would not know to check their maps), and
      // the internal-reflection term 4 (an older reader would evaluate the texels without it).
      {"version", MinimumVersion(m)},
      {"conventions", "docs/model.md version 1: z toward the camera, i toward the light (i.z < 0)"},
      {"btdf", MaterialModelName(m.model)},
      {"model", ModelFormula(m.model)},
      {"eta", m.eta},
      {"width", m.width},
      {"height", m.height},
      {"shadowing", "smith-ggx (roughness map; 0 = none)"},
      {"ndf", {{"kind", "tabulated-hemicube"}, {"resolution", m.ndf_resolution}, {"cells", grid.num_cells()},
               {"storage", "ln D, rows = representatives, columns = hemicube cells"}, {"table", "ndf_ln_d.exr"}}},
      {"representatives", {{"count", m.representative_texels.size()}, {"texels", m.representative_texels}}},
      {"maps", maps},
      {"provenance", m.provenance},
  };
  if (m.width_m > 0 && m.height_m > 0) manifest["sample"] = {{"width_m", m.width_m}, {"height_m", m.height_m}};
  if (m.internal_reflection) {
    manifest["internal_reflection"] = true;
    manifest["model"] = std::string(ModelFormula(m.model)) + " + k_s IR(alpha) (docs/model.md, \"Light reflected inside the slab\")";
  }
  common::WriteTextAtomically(folder / "material.json", manifest.dump(2) + "\n", false);
}

Material ReadMaterial(const fs::path& folder) {
  const fs::path manifest_path = folder / "material.json";
  const nlohmann::json manifest = common::ReadJsonFile(manifest_path);
  Material m;
  int version = 0;
  bool uncertainty = false;
  try {
    if (manifest.at("format") != "svbtdf-material") common::ThrowFormatError(manifest_path.string(), "is not an svbtdf material");
    version = common::IntegerAt(manifest, "version", manifest_path.string());
    if (version < 1 || version > kMaterialFormatVersion) {
      common::ThrowFormatError(manifest_path.string(), "has material format version " + std::to_string(version) +
                                                   "; this svbtdf reads version " + std::to_string(kMaterialFormatVersion));
    }
    m.model = ParseModel(manifest.value("btdf", "dual-microfacet"), manifest_path.string());
    m.eta = manifest.at("eta").get<double>();
    m.width = common::IntegerAt(manifest, "width", manifest_path.string());
    m.height = common::IntegerAt(manifest, "height", manifest_path.string());
    m.ndf_resolution = common::IntegerAt(manifest.at("ndf"), "resolution", manifest_path.string());
    if (manifest.contains("sample")) {
      m.width_m = manifest["sample"].at("width_m").get<double>();
      m.height_m = manifest["sample"].at("height_m").get<double>();
    }
    m.representative_texels = common::IntegerArrayAt<int64_t>(manifest.at("representatives"), "texels", manifest_path.string());
    m.provenance = manifest.value("provenance", nlohmann::json::object());
    if (!m.provenance.is_object()) common::ThrowFormatError(manifest_path.string(), "has a \"provenance\" that is not an object");
    uncertainty = manifest.contains("maps") && manifest["maps"].is_object() && manifest["maps"].contains("alpha_se");
    m.internal_reflection = manifest.value("internal_reflection", false);
  } catch (const nlohmann::json::exception& e) {
    common::ThrowFormatError(manifest_path.string(), std::string("misses a field or has a wrong type: ") + e.what());
  }
  if (m.width <= 0 || m.height <= 0 || !(m.eta > 1.0)) common::ThrowFormatError(manifest_path.string(), "has an invalid size or eta");
  if (!(m.width_m >= 0 && m.height_m >= 0 && std::isfinite(m.width_m) && std::isfinite(m.height_m))) {
    common::ThrowFormatError(manifest_path.string(), "has a sample size (\"sample\") that is not a finite size in metres");
  }
  // Every index a file gives is checked before it is used: a representative texel of 1e9 read far
  // out of bounds (SIGSEGV in `svbtdf eval`, issue 15), and 1024 or -1 read silently wrong texels.
  const int64_t texels = static_cast<int64_t>(m.width) * m.height;
  for (const int64_t texel : m.representative_texels) {
    if (texel < 0 || texel >= texels) {
      common::ThrowFormatError(manifest_path.string(), "lists representative texel " + std::to_string(texel) +
                                                           ", outside the " + std::to_string(m.width) + "x" +
                                                           std::to_string(m.height) + " material");
    }
  }
  if (m.ndf_resolution < 1 || m.ndf_resolution > 256) {
    common::ThrowFormatError(manifest_path.string(), "has an NDF resolution outside 1..256");
  }
  const model::Hemicube grid(m.ndf_resolution);
  const common::FloatImage tables = common::ReadFloatImage(folder / "ndf_ln_d.exr");
  common::RequireFinite(tables, (folder / "ndf_ln_d.exr").string());
  CheckShape(tables, grid.num_cells(), static_cast<int>(m.representative_texels.size()), 1,
             (folder / "ndf_ln_d.exr").string());
  for (int r = 0; r < tables.height; ++r) {
    std::vector<double> row(grid.num_cells());
    for (int c = 0; c < grid.num_cells(); ++c) row[c] = tables.at(c, r);
    m.representative_ln_d.push_back(std::move(row));
  }
  if (m.internal_reflection && (version < 4 || m.model != MaterialModel::kDualMicrofacet)) {
    common::ThrowFormatError(manifest_path.string(), version < 4 ? "asks for the internal-reflection term, which needs material format version 4"
                                                                 : "asks for the internal-reflection term, which only the dual-microfacet model has");
  }
  if (uncertainty && version < 3) {
    common::ThrowFormatError(manifest_path.string(), "lists standard-error maps, which need material format version 3");
  }
  for (const MapSpec& spec : MapsOf(m.model, uncertainty, version)) {
    const fs::path file = folder / spec.file;
    m.*spec.image = common::ReadFloatImage(file);
    common::RequireFinite(m.*spec.image, file.string());
    CheckShape(m.*spec.image, m.width, m.height, spec.channels, file.string());
  }
  if (m.weight_index.channels != m.weight_value.channels) {
    common::ThrowFormatError((folder / "weight_value.exr").string(), "has a different channel count than weight_index.exr");
  }
  const int reps = static_cast<int>(m.representative_texels.size());
  if (m.model == MaterialModel::kSlab && version < 5) {
    common::ThrowFormatError(manifest_path.string(), "has a slab btdf, which needs material format version 5");
  }
  if (m.model == MaterialModel::kSlab) {
    for (const MapSpec& spec : {kSlabMaps[0], kSlabMaps[1], kSlabMaps[2], kSlabMaps[3]}) {
      const common::FloatImage& map = m.*spec.image;
      if (*std::min_element(map.pixels.begin(), map.pixels.end()) <= 0.0f) {
        common::ThrowFormatError((folder / spec.file).string(), "holds a GGX roughness <= 0");
      }
    }
    if (version < 6) m.slab_longer_paths = common::FloatImage(m.width, m.height, 1);  // none before version 6
    for (const MapSpec& spec : {kSlabMaps[8], kSlabLongerPathsMap}) {
      const common::FloatImage& weights = m.*spec.image;
      if (*std::min_element(weights.pixels.begin(), weights.pixels.end()) < 0.0f) {
        common::ThrowFormatError((folder / spec.file).string(), "holds a negative weight");
      }
    }
  }
  if (m.model == MaterialModel::kWalterGgx) {
    for (const common::FloatImage* map : {&m.baseline_alpha_x, &m.baseline_alpha_y}) {
      if (*std::min_element(map->pixels.begin(), map->pixels.end()) <= 0.0f) {
        common::ThrowFormatError((folder / (map == &m.baseline_alpha_x ? "baseline_alpha_x.exr" : "baseline_alpha_y.exr")).string(),
                         "holds a GGX roughness <= 0");
      }
    }
  }
  for (float index : m.weight_index.pixels) {
    if (index < 0 || index >= reps || index != std::floor(index)) {
      common::ThrowFormatError((folder / "weight_index.exr").string(), "holds an index that is not a representative");
    }
  }
  return m;
}

model::DualMicrofacetParams TexelParams(const Material& material, int x, int y) {
  model::DualMicrofacetParams params;
  params.eta = material.eta;
  params.alpha = std::clamp<double>(material.alpha.at(x, y), 0.0, 1.0);
  const double roughness = material.shadowing_roughness.at(x, y);
  params.shadowing = roughness > 0 ? model::SmithShadowing::Ggx(roughness) : model::SmithShadowing::None();
  for (int c = 0; c < 3; ++c) {
    params.k_s[c] = material.k_s.at(x, y, c);
    params.rho_d[c] = material.rho_d.at(x, y, c);
  }
  params.internal_reflection = material.internal_reflection;
  return params;
}

SlabInterfaces TexelSlab(const Material& m, int x, int y) {
  return SlabInterfaces{{m.slab_entry_alpha_x.at(x, y), m.slab_entry_alpha_y.at(x, y), m.slab_entry_azimuth.at(x, y)},
                        {m.slab_exit_alpha_x.at(x, y), m.slab_exit_alpha_y.at(x, y), m.slab_exit_azimuth.at(x, y)},
                        m.slab_internal_reflection.at(x, y),
                        // A material built without the map (as before version 6) has no longer paths.
                        m.slab_longer_paths.width > 0 ? m.slab_longer_paths.at(x, y) : 0.0};
}

std::vector<double> RepresentativeScales(const Material& material) {
  // A representative's texel holds its own fit (weight 1 on itself).
  std::vector<double> scales;
  scales.reserve(material.representative_texels.size());
  for (const int64_t texel : material.representative_texels) {
    const int x = static_cast<int>(texel % material.width), y = static_cast<int>(texel / material.width);
    double scale = 0;
    for (int c = 0; c < 3; ++c) scale += material.k_s.at(x, y, c) / 3.0;
    scales.push_back(scale);
  }
  return scales;
}

MaterialEvaluator::MaterialEvaluator(const Material& material)
    : material_(material), grid_(material.ndf_resolution), representative_scale_(RepresentativeScales(material)) {
  // Every texel's NDF is a blend of these: exponentiate each table once, not once per texel.
  if (material.model == MaterialModel::kDualMicrofacet) {
    representative_d_.reserve(material.representative_ln_d.size());
    for (const auto& ln_d : material.representative_ln_d) {
      std::vector<float>& d = representative_d_.emplace_back(ln_d.size());
      for (size_t c = 0; c < ln_d.size(); ++c) d[c] = static_cast<float>(std::exp(ln_d[c]));
    }
  }
}

model::Rgb TexelBtdf::Evaluate(const model::Vec3& i, const model::Vec3& o) const {
  if (!baseline_ && !slab_) return model::EvaluateMaterial(ndf_, params_, i, o);
  const double shape = slab_ ? SlabShape(*slab_, params_.eta, i, o) : BaselineShape(*baseline_, params_.eta, i, o);
  model::Rgb value;
  for (int c = 0; c < 3; ++c) value[c] = params_.k_s[c] * shape + params_.rho_d[c];
  return value;
}

TexelBtdf TexelBtdf::UnitShape() const {
  model::DualMicrofacetParams unit = params_;
  unit.k_s = {1.0, 1.0, 1.0};
  unit.rho_d = {0.0, 0.0, 0.0};
  return TexelBtdf(ndf_, unit, baseline_, slab_);
}

std::optional<SlabInterfaces> MaterialEvaluator::Slab(int x, int y) const {
  if (material_.model != MaterialModel::kSlab) return std::nullopt;
  return TexelSlab(material_, x, y);
}

std::optional<BaselineLobe> MaterialEvaluator::Lobe(int x, int y) const {
  if (material_.model != MaterialModel::kWalterGgx) return std::nullopt;
  return BaselineLobe{material_.baseline_alpha_x.at(x, y), material_.baseline_alpha_y.at(x, y),
                      material_.baseline_azimuth.at(x, y)};
}

model::TabulatedNdf MaterialEvaluator::TexelNdf(int x, int y) const {
  // The baseline's texel NDF is its own interpolated lobe, the one Evaluate uses.
  if (const std::optional<BaselineLobe> lobe = Lobe(x, y)) return model::TabulatedNdf(grid_, BaselineLnD(grid_, *lobe));
  // A slab's is its exit interface's GGX (the tables hold the representatives' exits).
  if (const std::optional<SlabInterfaces> slab = Slab(x, y)) {
    return model::TabulatedNdf(grid_, BaselineLnD(grid_, {slab->exit.alpha_x, slab->exit.alpha_y, slab->exit.azimuth}));
  }
  std::vector<double> ln_d = TexelCellD(x, y);
  for (double& value : ln_d) value = std::log(value);
  model::TabulatedNdf ndf(grid_, std::move(ln_d));
  ndf.Normalize();
  return ndf;
}

std::vector<double> MaterialEvaluator::TexelCellD(int x, int y) const {
  // The representatives' D are blended scaled by their k_s, so that k_s D (what the data
  // constrain) is blended rather than each factor on its own: a representative whose fit put
  // much of D's mass where no dot looks, and a large k_s to compensate, then weighs in by what it
  // predicts. Blending D and k_s separately multiplied one representative's k_s with another's
  // D (held-out errors of 500% on a Monte Carlo truth, docs/validation.md).
  const int cells = grid_.num_cells();
  const auto blend = [&](bool by_scale, double* total_scale) {
    std::vector<double> d(cells, 0.0);
    *total_scale = 0;
    for (int k = 0; k < material_.weight_index.channels; ++k) {
      const double w = material_.weight_value.at(x, y, k);
      if (w == 0.0) continue;
      const size_t rep = static_cast<size_t>(material_.weight_index.at(x, y, k));
      const double scale = rep < representative_scale_.size() ? representative_scale_[rep] : 0.0;
      *total_scale += w * scale;
      const double weight = by_scale ? w * scale : w;
      const std::vector<float>& table = representative_d_.at(rep);
      for (int c = 0; c < cells; ++c) d[c] += weight * table[c];
    }
    return d;
  };
  double total_scale = 0;
  std::vector<double> d = blend(/*by_scale=*/true, &total_scale);
  // Representatives that transmit nothing (k_s = 0) leave the plain blend.
  if (!(total_scale > 0)) d = blend(/*by_scale=*/false, &total_scale);
  // Affine weights may be negative: keep D positive where the combination undershoots.
  const double floor = 1e-12 * std::max(total_scale, 1.0);
  for (double& value : d) value = std::max(value, floor);
  return d;
}

TexelBtdf MaterialEvaluator::Texel(int x, int y) const {
  if (x < 0 || y < 0 || x >= material_.width || y >= material_.height) {
    common::ThrowInvalidInput("--texel", "(" + std::to_string(x) + ", " + std::to_string(y) + ") is outside the " +
                                     std::to_string(material_.width) + "x" + std::to_string(material_.height) +
                                     " material");
  }
  return TexelBtdf(TexelNdf(x, y), TexelParams(material_, x, y), Lobe(x, y), Slab(x, y));
}

}  // namespace svbtdf::fit
