#pragma once
// The ground truth of a simulated session, DIR/truth/ (docs/truth-format.md), of either kind:
// the analytic dual-microfacet material of `svbtdf simulate --truth model` (a true alpha and
// NDF per texel) or the Monte Carlo slab truth of `--truth montecarlo` (a BTDF and rho_d only).
// `svbtdf compare`, `svbtdf report` and `svbtdf render` read truths through ReadTruth, so both accept both kinds.

#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "svbtdf/common/image_io.h"
#include "svbtdf/model/dual_microfacet.h"
#include "svbtdf/model/hemicube.h"
#include "svbtdf/simulate/montecarlo_truth.h"
#include "svbtdf/simulate/spatial_btdf.h"
#include "svbtdf/simulate/truth_material.h"
#include "svbtdf/simulate/truth_io.h"

namespace svbtdf::simulate {

class Truth {
 public:
  // The folder as it was given (named in the metrics and in errors).
  const std::filesystem::path& folder() const { return folder_; }
  // ReadTruthKind's answer: "analytic" or "montecarlo".
  const std::string& kind() const { return kind_; }
  // The camera, sample and dots of the capture (rig.json).
  const RigTruth& rig() const { return rig_; }
  int width() const { return btdf_->texels_x(); }
  int height() const { return btdf_->texels_y(); }

  // The analytic material's per-texel parameters, or nullptr for a Monte Carlo truth, which
  // has no alpha and no NDF to compare with.
  const MaterialTruth* parameters() const { return analytic_ ? &*analytic_ : nullptr; }
  // The Monte Carlo truth itself (its slab-material layout), or nullptr for an analytic truth.
  const MonteCarloTruth* montecarlo() const { return montecarlo_; }
  // The analytic truth as the simulator rendered it (its NDF objects and eta), or nullptr.
  const TruthMaterial* analytic_material() const { return analytic_material_; }
  // The BTDF of every texel, whichever the kind.
  const SpatialBtdf& btdf() const { return *btdf_; }

  model::Rgb RhoD(int x, int y) const;
  // rho_d of every texel as an RGB map, the shape of the material's own map.
  common::FloatImage RhoDMap() const;
  // R(x, i, o) of texel (x, y) as the renderer showed it to the camera.
  model::Rgb Evaluate(int x, int y, const model::Vec3& i, const model::Vec3& o) const { return btdf_->Evaluate(btdf_->Index(x, y), i, o); }

 private:
  friend Truth ReadTruth(const std::filesystem::path& folder);
  Truth() = default;

  std::filesystem::path folder_;
  std::string kind_;
  RigTruth rig_;
  std::optional<MaterialTruth> analytic_;
  const MonteCarloTruth* montecarlo_ = nullptr;  // owned by btdf_
  const TruthMaterial* analytic_material_ = nullptr;  // owned by btdf_
  std::unique_ptr<SpatialBtdf> btdf_;
};

// Reads DIR/truth/material.json (either kind, with its maps) and rig.json. Throws svbtdf::Error
// naming the file for anything missing or malformed, or a material.json of neither kind.
Truth ReadTruth(const std::filesystem::path& folder);

}  // namespace svbtdf::simulate
