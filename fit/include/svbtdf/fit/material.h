#pragma once
// A fitted svbtdf material on disk (docs/material-format.md, version 1): a folder with a JSON
// manifest and OpenEXR maps. Representatives carry full ln D tables; every texel is an affine
// combination of representatives (paper Sec. 4.3), whose weights also interpolate D linearly.

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <vector>

#include <nlohmann/json.hpp>

#include "svbtdf/common/image_io.h"
#include "svbtdf/fit/baseline_fit.h"
#include "svbtdf/fit/clustering.h"
#include "svbtdf/fit/slab_fit.h"
#include "svbtdf/fit/texel_fit.h"
#include "svbtdf/model/dual_microfacet.h"
#include "svbtdf/model/hemicube.h"
#include "svbtdf/model/tabulated_ndf.h"

namespace svbtdf::fit {

// Version 2 adds the single-interface baseline (manifest "btdf": "walter-ggx"). Version 3 adds
// the per-texel standard errors (the *_se maps). Version 4 adds the light reflected inside the
// slab (manifest "internal_reflection": true). Version 5 adds the slab model (manifest "btdf":
// "slab", `svbtdf fit --model slab`). Version 6 adds the slab's longer internal paths (the map
// slab_longer_paths; a version 5 slab has none). A material is written with the lowest version
// that describes it: 6 for a slab, 4 with that term, else 3 with standard errors, else 2 for the
// baseline, else 1, so that older readers keep reading what they can.
inline constexpr int kMaterialFormatVersion = 6;

// Which BTDF the material's texels hold.
enum class MaterialModel {
  kDualMicrofacet,  // the paper's model: NDF table, alpha, shadowing
  kWalterGgx,       // the baseline (`svbtdf fit --model ggx`): one rough refraction, anisotropic GGX
  kSlab,            // `svbtdf fit --model slab`: two rough interfaces, a GGX roughness each
};

struct Material {
  MaterialModel model = MaterialModel::kDualMicrofacet;
  int width = 0, height = 0;   // texels
  double eta = 1.5;
  // The sample's physical size in metres (the store's geometry; "sample" in material.json), which
  // a renderer needs; 0 when not recorded (materials written before it was).
  double width_m = 0.0, height_m = 0.0;
  int ndf_resolution = 32;
  // Per-representative fits.
  std::vector<int64_t> representative_texels;        // texel index (y * width + x)
  std::vector<std::vector<double>> representative_ln_d;  // num_cells values each, normalised
  // Per-texel maps (interpolated for non-representatives).
  common::FloatImage alpha;                // 1 channel
  common::FloatImage shadowing_roughness;  // 1 channel; 0 = no shadowing
  common::FloatImage k_s;                  // 3 channels
  common::FloatImage rho_d;                // 3 channels
  common::FloatImage residual;             // 1 channel: relative RMSE of the texel's own samples (-1: not fitted)
  common::FloatImage cluster;              // 1 channel: the representative of the texel's cluster
  // Affine weights: K channels of representative indices and K of weights (sum 1; unused: 0, 0).
  common::FloatImage weight_index;
  common::FloatImage weight_value;
  // kWalterGgx only (1 channel each, interpolated like alpha): the GGX lobe of every texel. The NDF
  // tables then hold that lobe tabulated, and alpha and the shadowing roughness are unused (0).
  common::FloatImage baseline_alpha_x, baseline_alpha_y, baseline_azimuth;
  // kSlab only (1 channel each): every texel's two interfaces (SlabSide: alpha_x, alpha_y and
  // the azimuth of the first axis per side), the standard errors of each side's Roughness()
  // (-1: not known) and the internal reflection's weight. The NDF tables then hold the exit's
  // GGX, and alpha and the shadowing roughness are unused (0).
  common::FloatImage slab_entry_alpha_x, slab_entry_alpha_y, slab_entry_azimuth;
  common::FloatImage slab_exit_alpha_x, slab_exit_alpha_y, slab_exit_azimuth;
  common::FloatImage slab_entry_roughness_se, slab_exit_roughness_se;
  common::FloatImage slab_internal_reflection;  // SlabInterfaces::internal_reflection (>= 0)
  common::FloatImage slab_longer_paths;         // SlabInterfaces::longer_paths (>= 0; version 6)
  // Version 3, dual-microfacet: standard errors per texel (docs/fitting.md, "Uncertainty"); all
  // empty (0 x 0) in a material without them. -1 where not known.
  common::FloatImage alpha_se;                // 1 channel
  common::FloatImage k_s_se;                  // 3 channels
  common::FloatImage rho_d_se;                // 3 channels
  common::FloatImage shadowing_roughness_se;  // 1 channel
  common::FloatImage ndf_width_se;            // 1 channel: of ndf_width
  common::FloatImage ndf_width;               // 1 channel: the texel's NDF width (RMS tangent of its half vectors)
  // 1 channel: the predicted error of the texel's BTDF against the truth, relative RMS over its
  // own samples, from the standard errors of its fitted parameters.
  common::FloatImage prediction_se;
  bool has_uncertainty() const { return alpha_se.width > 0; }
  // Version 4, dual-microfacet: every texel's rho includes the light reflected once by each
  // interface inside the slab (DualMicrofacetParams::internal_reflection; `svbtdf fit
  // --internal-reflection`).
  bool internal_reflection = false;
  nlohmann::json provenance = nlohmann::json::object();  // session, settings, statistics, holdout
};

// Assembles a material from the representatives' fits (in the order of clustering.representatives)
// and every texel's affine weights: alpha, shadowing roughness, k_s and D are interpolated with
// the weights; rho_d is the texel's own (measured directly, no fit needed).
Material AssembleMaterial(int width, int height, double eta, int ndf_resolution, const Clustering& clustering,
                          const std::vector<TexelFitResult>& representative_fits, const common::FloatImage& rho_d);

// The same for the baseline (`svbtdf fit --model ggx`): a kWalterGgx material in which every
// texel takes the fit of its cluster's representative (weight 1; see material.cc for why not the
// affine blend).
Material AssembleBaselineMaterial(int width, int height, double eta, int ndf_resolution, const Clustering& clustering,
                                  const std::vector<BaselineFitResult>& representative_fits, const common::FloatImage& rho_d);

// The same for the slab model (`svbtdf fit --model slab`): every texel takes its cluster's
// representative's interfaces, as the baseline does.
Material AssembleSlabMaterial(int width, int height, double eta, int ndf_resolution, const Clustering& clustering,
                              const std::vector<SlabFitResult>& representative_fits, const common::FloatImage& rho_d);

// "dual-microfacet" | "walter-ggx" | "slab", as in the manifest's "btdf" field.
const char* MaterialModelName(MaterialModel model);

// Writes MATERIAL/ (a new or empty folder; an existing material is never overwritten).
void WriteMaterial(const std::filesystem::path& folder, const Material& material);
// Reads and checks a material; every problem is an svbtdf::Error naming the file.
Material ReadMaterial(const std::filesystem::path& folder);

// Texel (x, y)'s dual-microfacet parameters as every evaluator of a material takes them: the
// material's eta, alpha clamped to [0, 1], the Smith roughness (0: no shadowing), k_s, rho_d and
// whether rho includes the light reflected inside the slab.
model::DualMicrofacetParams TexelParams(const Material& material, int x, int y);

// Texel (x, y)'s two interfaces and internal-reflection weight, for a slab material.
SlabInterfaces TexelSlab(const Material& material, int x, int y);

// Each representative's scale s_j (its own texel's k_s, channel mean), by which a texel's blend
// weighs the representative's D (docs/material-format.md).
std::vector<double> RepresentativeScales(const Material& material);

// One texel of a material, ready to evaluate at many direction pairs.
// For the baseline, `params` holds eta, k_s and rho_d, and `baseline` the lobe:
//   R[c] = k_s[c] BaselineShape(lobe, eta, i, o) + rho_d[c];
// for the slab model, `slab` the interfaces: R[c] = k_s[c] SlabShape(slab, eta, i, o) + rho_d[c].
class TexelBtdf {
 public:
  TexelBtdf(model::TabulatedNdf ndf, model::DualMicrofacetParams params, std::optional<BaselineLobe> baseline = std::nullopt,
            std::optional<SlabInterfaces> slab = std::nullopt)
      : ndf_(std::move(ndf)), params_(params), baseline_(baseline), slab_(slab) {}
  model::Rgb Evaluate(const model::Vec3& i, const model::Vec3& o) const;
  const model::TabulatedNdf& ndf() const { return ndf_; }
  const model::DualMicrofacetParams& params() const { return params_; }
  MaterialModel model() const {
    return slab_ ? MaterialModel::kSlab : baseline_ ? MaterialModel::kWalterGgx : MaterialModel::kDualMicrofacet;
  }
  const std::optional<BaselineLobe>& baseline() const { return baseline_; }
  const std::optional<SlabInterfaces>& slab() const { return slab_; }
  // The same texel with k_s = 1 and rho_d = 0: its shape.
  TexelBtdf UnitShape() const;

 private:
  model::TabulatedNdf ndf_;
  model::DualMicrofacetParams params_;
  std::optional<BaselineLobe> baseline_;
  std::optional<SlabInterfaces> slab_;
};

// Evaluates R(x, i, o) for any texel: D = sum of w_j D_j over the texel's representatives.
class MaterialEvaluator {
 public:
  explicit MaterialEvaluator(const Material& material);
  // The texel's BTDF. Building it normalises its NDF table: reuse it for many directions.
  // Throws svbtdf::Error(kInvalidInput) for a texel outside the material.
  TexelBtdf Texel(int x, int y) const;
  // One-off evaluation (builds the texel each call).
  model::Rgb Evaluate(int x, int y, const model::Vec3& i, const model::Vec3& o) const { return Texel(x, y).Evaluate(i, o); }
  // The texel's own NDF table: the weighted sum of the representatives' D, each scaled by its
  // transmission scale k_s (docs/material-format.md), normalised.
  model::TabulatedNdf TexelNdf(int x, int y) const;
  // The dual-microfacet texel's blend at the hemicube's cells before TexelNdf interpolates and
  // normalises it: d_c of docs/material-format.md, clamped, positive, in an arbitrary scale (one
  // value per cell of Hemicube(ndf_resolution)). For a dual-microfacet material only: a
  // walter-ggx texel's lobe is in its baseline maps.
  std::vector<double> TexelCellD(int x, int y) const;
  // The scale a representative's D is weighted by in TexelNdf (its own k_s, channel mean).
  double RepresentativeScale(int representative) const { return representative_scale_.at(representative); }

 private:
  std::optional<BaselineLobe> Lobe(int x, int y) const;  // the texel's lobe, for a walter-ggx material
  std::optional<SlabInterfaces> Slab(int x, int y) const;  // the texel's interfaces, for a slab material

  const Material& material_;
  model::Hemicube grid_;
  std::vector<double> representative_scale_;  // mean k_s of each representative's own fit
  std::vector<std::vector<float>> representative_d_;  // exp of representative_ln_d (dual-microfacet)
};

}  // namespace svbtdf::fit
