#include "svbtdf/simulate/truth.h"

#include "svbtdf/common/error.h"
#include "svbtdf/simulate/truth_material.h"

namespace svbtdf::simulate {

model::Rgb SpatialBtdf::EvaluatePolarised(int, const model::Vec3&, const model::Vec3&, const model::Vec3&) const {
  common::ThrowInvalidInput("--monitor-polarization", "this truth cannot render polarised light",
                            "polarised monitors are simulated with the analytic truth (--truth model) only");
}

Truth ReadTruth(const std::filesystem::path& folder) {
  Truth truth;
  truth.folder_ = folder;
  truth.kind_ = ReadTruthKind(folder);
  if (truth.kind_ == "montecarlo") {
    auto montecarlo = std::make_unique<MonteCarloTruth>(ReadMonteCarloTruth(folder));
    truth.montecarlo_ = montecarlo.get();
    truth.btdf_ = std::move(montecarlo);
  } else {
    truth.analytic_.emplace(ReadMaterialTruth(folder));
    auto material = std::make_unique<TruthMaterial>(truth.analytic_->ToTruthMaterial());
    truth.analytic_material_ = material.get();
    truth.btdf_ = std::move(material);
  }
  truth.rig_ = ReadRigTruth(folder / "rig.json");
  return truth;
}

model::Rgb Truth::RhoD(int x, int y) const {
  return analytic_ ? analytic_->Params(x, y).rho_d : montecarlo_->rho_d(montecarlo_->Index(x, y));
}

common::FloatImage Truth::RhoDMap() const {
  if (analytic_) return analytic_->rho_d;
  common::FloatImage map(width(), height(), 3);
  for (int y = 0; y < height(); ++y) {
    for (int x = 0; x < width(); ++x) {
      const model::Rgb rho_d = RhoD(x, y);
      for (int c = 0; c < 3; ++c) map.at(x, y, c) = static_cast<float>(rho_d[c]);
    }
  }
  return map;
}

}  // namespace svbtdf::simulate
