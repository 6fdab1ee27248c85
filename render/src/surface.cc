#include "svbtdf/render/surface.h"

#include <algorithm>
#include <utility>
#include <cmath>

#include "svbtdf/common/error.h"
#include "svbtdf/common/json.h"
#include "svbtdf/model/hemicube.h"

namespace svbtdf::render {
namespace fs = std::filesystem;

Surface::Surface(int texels_x, int texels_y, double width_m, double height_m, const std::string& source)
    : texels_x_(texels_x), texels_y_(texels_y), width_m_(width_m), height_m_(height_m) {
  if (texels_x <= 0 || texels_y <= 0) common::ThrowInvalidInput(source, "has no texels");
  if (!(width_m > 0 && height_m > 0 && std::isfinite(width_m) && std::isfinite(height_m))) {
    common::ThrowInvalidInput(source, "has no physical size (give --sample-size WIDTH HEIGHT in metres)");
  }
}

// ---------------------------------------------------------------------------------------------
// MaterialSurface

MaterialSurface::MaterialSurface(const fit::Material& material, double width_m, double height_m, const std::string& source)
    : Surface(material.width, material.height, width_m, height_m, source),
      material_(material),
      representative_scale_(fit::RepresentativeScales(material)),
      clamped_integral_(static_cast<size_t>(material.width) * material.height) {
  const model::Hemicube grid(material.ndf_resolution);
  representatives_.reserve(material.representative_ln_d.size());
  for (const std::vector<double>& ln_d : material.representative_ln_d) {
    // The stored tables are normalised under TabulatedNdf's own quadrature, so a blend whose
    // weights sum to 1 is normalised too. Renormalising guards tables written by hand.
    representatives_.emplace_back(grid, ln_d).Normalize();
  }
  if (material.weight_index.channels > model::TabulatedNdfBlend::kMaxComponents) {
    common::ThrowFormatError(source, "blends more representatives per texel than the renderer takes (" +
                                         std::to_string(material.weight_index.channels) + ")");
  }
}

std::string MaterialSurface::description() const {
  return std::string("fitted ") + fit::MaterialModelName(material_.model) + " material";
}

const model::Bsdf& MaterialSurface::At(int col, int row, BsdfScratch& scratch) const {
  const fit::Material& m = material_;
  const model::DualMicrofacetParams params = fit::TexelParams(m, col, row);
  if (m.model == fit::MaterialModel::kWalterGgx) {
    scratch.ggx.emplace(m.baseline_alpha_x.at(col, row), m.baseline_alpha_y.at(col, row));
    return scratch.walter.emplace(*scratch.ggx, 1.0, m.eta, params.k_s, params.rho_d, m.baseline_azimuth.at(col, row));
  }
  if (m.model == fit::MaterialModel::kSlab) {
    const fit::SlabInterfaces slab = fit::TexelSlab(m, col, row);
    const fit::SlabNdfs& sides = scratch.slab_sides.emplace(slab);
    model::SlabInternalLight internal{slab.internal_reflection, slab.longer_paths};
    if (slab.longer_paths > 0) {
      const fit::SlabNdfs& longer = scratch.slab_longer_sides.emplace(slab, model::kLongerPathsWidening);
      internal.longer_entry = &longer.entry();
      internal.longer_exit = &longer.exit();
    }
    return scratch.slab.emplace(sides.entry(), sides.exit(), m.eta, params.k_s, params.rho_d, internal);
  }
  // D = sum_j c_j D_j with c_j = w_j s_j / S, as MaterialEvaluator::TexelNdf blends the cells
  // (docs/material-format.md), except that the sum is taken after interpolation.
  struct Term {
    int representative;
    double weight;
  };
  std::array<Term, model::TabulatedNdfBlend::kMaxComponents> terms{};
  int count = 0;
  double scaled_total = 0, plain_total = 0;
  for (int k = 0; k < m.weight_index.channels; ++k) {
    const double w = m.weight_value.at(col, row, k);
    if (w == 0.0) continue;
    const int rep = static_cast<int>(m.weight_index.at(col, row, k));
    terms[count++] = {rep, w};
    scaled_total += w * representative_scale_[rep];
    plain_total += w;
  }
  const bool by_scale = scaled_total > 0;  // representatives that transmit nothing: the plain blend
  const auto normalised_weight = [&](const Term& term) {
    return term.weight * (by_scale ? representative_scale_[term.representative] / scaled_total : 1.0 / plain_total);
  };
  bool negative = false;
  for (int t = 0; t < count; ++t) negative = negative || normalised_weight(terms[t]) < 0;
  // The weights sum to 1 and every table is normalised, so the blend is too, until negative
  // weights are clamped away: that adds mass, which can be many times the blend's own when its
  // terms nearly cancel. Such a texel is scaled back by its clamped blend's integral, as
  // MaterialEvaluator::TexelNdf normalises its clamped table.
  double scale = 1.0;
  if (negative) {
    const size_t index = static_cast<size_t>(row) * m.width + col;
    float integral = clamped_integral_[index].load(std::memory_order_relaxed);
    if (integral == 0.0f) {
      std::array<int, model::TabulatedNdfBlend::kMaxComponents> reps{};
      std::array<double, model::TabulatedNdfBlend::kMaxComponents> weights{};
      for (int t = 0; t < count; ++t) reps[t] = terms[t].representative, weights[t] = normalised_weight(terms[t]);
      integral = static_cast<float>(ClampedIntegral(reps.data(), weights.data(), count));
      clamped_integral_[index].store(integral, std::memory_order_relaxed);
    }
    scale = 1.0 / integral;
  }
  model::TabulatedNdfBlend& blend = scratch.blend.emplace();
  for (int t = 0; t < count; ++t) blend.Add(representatives_[terms[t].representative], normalised_weight(terms[t]) * scale);
  return scratch.dual.emplace(blend, params, &blend);
}

double MaterialSurface::ClampedIntegral(const int* representatives, const double* weights, int count) const {
  // The unclamped blend integrates to exactly 1 (normalised tables, weights summing to 1), so only
  // the mass the clamp adds is computed: the integral of max(0, -sum) by 2 x 2 points per cell of
  // the tables' hemicube, taken as the clamped minus the signed sum under the same rule so that
  // the rule's own error cancels (about 1 ms per texel at resolution 32, 4 representatives).
  const model::Hemicube& grid = representatives_.front().grid();
  constexpr int kSub = 2;
  double clamped = 0, signed_sum = 0;
  for (int c = 0; c < grid.num_cells(); ++c) {
    const double cell_weight = grid.CellSolidAngle(c) / (kSub * kSub);
    for (int a = 0; a < kSub; ++a) {
      for (int b = 0; b < kSub; ++b) {
        const model::Vec3 h = grid.CellPoint(c, (a + 0.5) / kSub, (b + 0.5) / kSub);
        double d = 0;
        for (int j = 0; j < count; ++j) d += weights[j] * representatives_[representatives[j]].D(h);
        clamped += std::max(d, 0.0) * h.z() * cell_weight;
        signed_sum += d * h.z() * cell_weight;
      }
    }
  }
  return 1.0 + std::max(0.0, clamped - signed_sum);
}

// ---------------------------------------------------------------------------------------------
// TruthSurface

TruthSurface::TruthSurface(const simulate::Truth& truth)
    : Surface(truth.width(), truth.height(), truth.rig().sample.width, truth.rig().sample.height(),
              truth.folder().string()),
      truth_(truth) {}

std::string TruthSurface::description() const { return truth_.kind() + " truth"; }

const model::Bsdf& TruthSurface::At(int col, int row, BsdfScratch& scratch) const {
  const int index = truth_.btdf().Index(col, row);
  if (const simulate::TruthMaterial* analytic = truth_.analytic_material()) {
    return scratch.dual.emplace(analytic->ndf(index), truth_.parameters()->Params(col, row));
  }
  const simulate::SpatialBtdf* btdf = &truth_.btdf();
  return scratch.evaluated.emplace(
      [btdf, index](const model::Vec3& i, const model::Vec3& o) { return btdf->Evaluate(index, i, o); });
}

// ---------------------------------------------------------------------------------------------
// LobeSurface

LobeSurface::LobeSurface(const fit::Material& material, common::FloatImage alpha_x, common::FloatImage alpha_y,
                         common::FloatImage azimuth, double width_m, double height_m, const std::string& source)
    : Surface(material.width, material.height, width_m, height_m, source),
      material_(material),
      alpha_x_(std::move(alpha_x)),
      alpha_y_(std::move(alpha_y)),
      azimuth_(std::move(azimuth)) {
  if (material.model != fit::MaterialModel::kDualMicrofacet) {
    common::ThrowInvalidInput(source, std::string("is a ") + fit::MaterialModelName(material.model) +
                                          " material: only a dual-microfacet material's NDF tables are fitted by lobes");
  }
  for (const common::FloatImage* map : {&alpha_x_, &alpha_y_, &azimuth_}) {
    if (map->width != material.width || map->height != material.height || map->channels != 1) {
      common::ThrowInvalidInput(source, "has lobe maps of another size than the material");
    }
  }
}

std::string LobeSurface::description() const { return "fitted dual-microfacet material, GGX lobe per texel"; }

const model::Bsdf& LobeSurface::At(int col, int row, BsdfScratch& scratch) const {
  // The Ellipsoid NDF with no skew is anisotropic GGX turned by theta_z; it turns the lobe's x
  // axis to -theta_z (A^-T = S^-1 Rz(theta_z)), hence the minus.
  const model::Ndf& ndf = scratch.ellipsoid.emplace(alpha_x_.at(col, row), alpha_y_.at(col, row), 0.0, 0.0,
                                                    -static_cast<double>(azimuth_.at(col, row)));
  return scratch.dual.emplace(ndf, fit::TexelParams(material_, col, row));
}

// ---------------------------------------------------------------------------------------------

LoadedSurface LoadSurface(const fs::path& folder, std::optional<std::pair<double, double>> sample_size) {
  const fs::path manifest_path = folder / "material.json";
  if (!fs::is_regular_file(manifest_path)) {
    common::ThrowInvalidInput(folder.string(), "is not a material or a truth folder (it has no material.json)");
  }
  const nlohmann::json manifest = common::ReadJsonFile(manifest_path);
  LoadedSurface loaded;
  if (manifest.is_object() && manifest.value("format", "") == "svbtdf-material") {
    loaded.material_ = std::make_unique<fit::Material>(fit::ReadMaterial(folder));
    const fit::Material& m = *loaded.material_;
    const auto [width_m, height_m] = sample_size.value_or(std::pair{m.width_m, m.height_m});
    loaded.surface_ = std::make_unique<MaterialSurface>(m, width_m, height_m, manifest_path.string());
    return loaded;
  }
  if (sample_size) {
    common::ThrowInvalidInput("--sample-size", "applies to a fitted material only: " + folder.string() +
                                                   " is a truth, whose rig.json records the sample's size");
  }
  loaded.truth_ = std::make_unique<simulate::Truth>(simulate::ReadTruth(folder));
  loaded.surface_ = std::make_unique<TruthSurface>(*loaded.truth_);
  return loaded;
}

}  // namespace svbtdf::render
