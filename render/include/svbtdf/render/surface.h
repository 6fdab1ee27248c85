#pragma once
// The planar sample as a renderer sees it: a grid of texels of a physical size, each with its
// BSDF (model/bsdf.h). A fitted material (fit/) and both kinds of simulator truth (simulate/)
// are surfaces, so `svbtdf render` draws any of them with the same camera and scene.
//
// Renderers ask for one texel's BSDF per hit; At() builds it in a caller-owned scratch (one per
// thread), so that nothing is allocated per hit and the material's tables are built once.

#include <atomic>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "svbtdf/fit/material.h"
#include "svbtdf/fit/slab_fit.h"
#include "svbtdf/model/bsdf.h"
#include "svbtdf/model/ellipsoid_ndf.h"
#include "svbtdf/model/ggx.h"
#include "svbtdf/model/ndf_blend.h"
#include "svbtdf/model/tabulated_ndf.h"
#include "svbtdf/simulate/truth.h"

namespace svbtdf::render {

// Room for whichever BSDF a surface builds at a texel; reused from hit to hit by one thread.
struct BsdfScratch {
  std::optional<model::TabulatedNdfBlend> blend;
  std::optional<model::GgxNdf> ggx;
  std::optional<model::EllipsoidNdf> ellipsoid;  // a rotated GGX lobe (LobeSurface)
  std::optional<fit::SlabNdfs> slab_sides, slab_longer_sides;  // a slab texel's, and widened
  std::optional<model::DualMicrofacetBsdf> dual;
  std::optional<model::WalterBsdf> walter;
  std::optional<model::SlabBsdf> slab;
  std::optional<model::EvaluatedBsdf> evaluated;
};

class Surface {
 public:
  virtual ~Surface() = default;

  int texels_x() const { return texels_x_; }
  int texels_y() const { return texels_y_; }
  double width_m() const { return width_m_; }
  double height_m() const { return height_m_; }
  // What the surface is, for messages and the image's metadata ("fitted dual-microfacet material", ...).
  virtual std::string description() const = 0;

  // The BSDF of texel (col, row), valid until the next call with the same scratch.
  virtual const model::Bsdf& At(int col, int row, BsdfScratch& scratch) const = 0;

 protected:
  // Throws svbtdf::Error(kInvalidInput) naming `source` unless the size is finite and positive.
  Surface(int texels_x, int texels_y, double width_m, double height_m, const std::string& source);

 private:
  int texels_x_, texels_y_;
  double width_m_, height_m_;
};

// A fitted material: the dual-microfacet texel with D the blend of its representatives' tables
// (model::TabulatedNdfBlend, sampled as their mixture), or the walter-ggx baseline's texel.
// `material` must outlive the surface. At() is safe to call from many threads at once.
class MaterialSurface final : public Surface {
 public:
  MaterialSurface(const fit::Material& material, double width_m, double height_m, const std::string& source);
  std::string description() const override;
  const model::Bsdf& At(int col, int row, BsdfScratch& scratch) const override;

 private:
  // The integral of D h.z of the blend sum_j weights[j] D_j clamped at 0, for weights summing to 1.
  double ClampedIntegral(const int* representatives, const double* weights, int count) const;

  const fit::Material& material_;
  std::vector<model::TabulatedNdf> representatives_;  // each representative's own table
  std::vector<double> representative_scale_;          // fit::RepresentativeScales
  // Per texel with a negative weight, the integral of its clamped blend, computed on first use
  // (0: not yet). A pure function of the texel, so whichever thread computes it stores the same.
  mutable std::vector<std::atomic<float>> clamped_integral_;
};

// A fitted dual-microfacet material with every texel's tabulated NDF replaced by an anisotropic
// GGX lobe (alpha_x along an axis at `azimuth` radians from +x, alpha_y across it: the lobes
// `svbtdf export` fits, exporter::MaterialLobes): alpha, shadowing, k_s and rho_d stay the
// material's, so a render against MaterialSurface's measures what the lobe fit alone loses
// (`svbtdf render --parametric`, docs/export.md). `material` must outlive the surface.
class LobeSurface final : public Surface {
 public:
  // Throws svbtdf::Error(kInvalidInput) naming `source` for a walter-ggx material (its texels are
  // GGX lobes already) or lobe maps of another size than the material.
  LobeSurface(const fit::Material& material, common::FloatImage alpha_x, common::FloatImage alpha_y,
              common::FloatImage azimuth, double width_m, double height_m, const std::string& source);
  std::string description() const override;
  const model::Bsdf& At(int col, int row, BsdfScratch& scratch) const override;

 private:
  const fit::Material& material_;
  common::FloatImage alpha_x_, alpha_y_, azimuth_;
};

// A simulator truth (either kind): the analytic dual-microfacet texel with its own NDF, or the
// Monte Carlo truth's traced BTDF, evaluate-only and sampled by the cosine. `truth` must
// outlive the surface.
class TruthSurface final : public Surface {
 public:
  explicit TruthSurface(const simulate::Truth& truth);
  std::string description() const override;
  const model::Bsdf& At(int col, int row, BsdfScratch& scratch) const override;

 private:
  const simulate::Truth& truth_;
};

// A material or truth folder read from disk, with the surface built on it.
class LoadedSurface {
 public:
  const Surface& surface() const { return *surface_; }

 private:
  friend LoadedSurface LoadSurface(const std::filesystem::path&, std::optional<std::pair<double, double>>);
  std::unique_ptr<fit::Material> material_;
  std::unique_ptr<simulate::Truth> truth_;
  std::unique_ptr<Surface> surface_;
};

// Reads FOLDER as a fitted material (material.json of format svbtdf-material) or a simulator
// truth (OUT/truth). `sample_size` (metres) overrides the recorded size, and is needed for a
// material written before materials recorded it. Every problem is an svbtdf::Error naming the file.
LoadedSurface LoadSurface(const std::filesystem::path& folder,
                          std::optional<std::pair<double, double>> sample_size = std::nullopt);

}  // namespace svbtdf::render
