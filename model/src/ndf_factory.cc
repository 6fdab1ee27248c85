#include "svbtdf/model/ndf_factory.h"

#include <string>

#include "svbtdf/common/error.h"
#include "svbtdf/model/beckmann.h"
#include "svbtdf/model/ellipsoid_ndf.h"
#include "svbtdf/model/ggx.h"
#include "svbtdf/model/vmf_ndf.h"

namespace svbtdf::model {

std::vector<std::string> AnalyticNdfNames() { return {"ggx", "beckmann", "ellipsoid", "vmf"}; }

std::unique_ptr<Ndf> MakeAnalyticNdf(std::string_view name, const AnalyticNdfParams& params) {
  if (name == "ggx") return std::make_unique<GgxNdf>(params.alpha_x, params.alpha_y);
  if (name == "beckmann") return std::make_unique<BeckmannNdf>(params.alpha_x, params.alpha_y);
  if (name == "ellipsoid") {
    return std::make_unique<EllipsoidNdf>(params.alpha_x, params.alpha_y, params.theta_x, params.theta_y, params.theta_z);
  }
  if (name == "vmf") return std::make_unique<VmfNdf>(params.mean, params.kappa);
  std::string known;
  for (const std::string& n : AnalyticNdfNames()) known += (known.empty() ? "" : ", ") + n;
  common::ThrowInvalidInput("ndf", "unknown NDF '" + std::string(name) + "'", "known: " + known);
}

}  // namespace svbtdf::model
