#pragma once
// The ground-truth material the simulator renders (docs/truth-format.md): per texel an analytic
// NDF, the dual-microfacet blend weight alpha, the Smith shadowing roughness, an RGB k_s and an
// RGB diffuse rho_d, with one eta for the sample,
//     R(x, i, o)[c] = k_s[c] rho(i, o; NDF(x), alpha(x), shadowing(x)) + rho_d[c]
// (docs/model.md, "The blend"). Texel (col, row) is centred at Rig::TexelCentre(col, row).

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "svbtdf/model/dual_microfacet.h"
#include "svbtdf/model/ndf.h"
#include "svbtdf/model/ndf_factory.h"
#include "svbtdf/model/vec.h"
#include "svbtdf/simulate/spatial_btdf.h"

namespace svbtdf::simulate {

struct TruthTexel {
  model::AnalyticNdfParams ndf;            // ggx/ellipsoid parameters (alpha_x, alpha_y, theta_*)
  double alpha = 0.5;               // blend weight of the rough-entry term
  double shadowing_roughness = 0.0; // 0: no shadowing (indicators only)
  model::Rgb k_s = {1.0, 1.0, 1.0};
  model::Rgb rho_d = {0.0, 0.0, 0.0};
};

// The spatial patterns the presets use; each is a smooth function of the texel position and a
// seed, so that a truth can be regenerated from (pattern, size, eta, seed).
//   smooth      moderate isotropic roughness varying smoothly, mild colour (tiny, demo)
//   grid-sheet  strongly anisotropic GGX whose long axis swaps on the lines of a grid
//   leaf-glass  rough leaf-shaped patches on smooth glass
//   rice-paper  fibrous rough paper, coloured k_s and a diffuse part
//   diffuser    a flat Lambertian transmitter (rho_d 0.1, k_s 0): the emission calibration's sample
std::vector<std::string> TruthPatternNames();

class TruthMaterial final : public SpatialBtdf {
 public:
  // Throws svbtdf::Error(kInvalidInput) for a bad size, eta or NDF name.
  TruthMaterial(int texels_x, int texels_y, double eta, std::string ndf_name,
                std::vector<TruthTexel> texels);

  static TruthMaterial FromPattern(const std::string& pattern, int texels_x, int texels_y,
                                   double eta, uint64_t seed);

  int texels_x() const override { return texels_x_; }
  int texels_y() const override { return texels_y_; }
  double eta() const { return eta_; }
  const std::string& ndf_name() const { return ndf_name_; }
  const TruthTexel& texel(int col, int row) const { return texels_[Index(col, row)]; }
  const TruthTexel& texel(int index) const { return texels_[index]; }
  const model::Ndf& ndf(int index) const { return *ndfs_[index]; }

  // R(x, i, o) of texel `index` for unit i (toward the light, i.z < 0) and o (toward the camera).
  model::Rgb Evaluate(int index, const model::Vec3& i, const model::Vec3& o) const override;
  // Each configuration's Fresnel product replaced by the power its two interfaces transmit of the
  // polarised field (model::DualMicrofacetModel::RoughEntry's `field`); rho_d is unpolarised.
  model::Rgb EvaluatePolarised(int index, const model::Vec3& i, const model::Vec3& o,
                               const model::Vec3& field) const override;

  // The smallest NDF roughness of a texel: how sharp its lobe can be (for quadrature choices).
  double MinRoughness(int index) const override;

  // A GGX texel's larger D(h) / D(z) of its two configurations' half vectors (z is the GGX's peak;
  // 0 where neither is valid, as rho is then 0 whatever i). 1 for every other NDF: Beckmann's
  // tail is not GGX's, and an ellipsoid's peak may be skewed off z.
  double LobeFraction(int index, const model::Vec3& i, const model::Vec3& o) const override;

 private:
  int texels_x_;
  int texels_y_;
  double eta_;
  std::string ndf_name_;
  std::vector<TruthTexel> texels_;
  std::vector<std::unique_ptr<model::Ndf>> ndfs_;
  std::vector<model::DualMicrofacetModel> models_;  // per texel: eta and its shadowing
  std::vector<double> lobe_peaks_;  // per texel: D(z) of a GGX truth (LobeFraction); empty otherwise
};

}  // namespace svbtdf::simulate
