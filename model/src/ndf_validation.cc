#include "svbtdf/model/ndf_validation.h"

#include <cmath>

#include "svbtdf/common/error.h"

namespace svbtdf::model {

void RequirePositiveRoughness(const std::string& ndf_name, double alpha_x, double alpha_y) {
  for (const double alpha : {alpha_x, alpha_y}) {
    if (!(alpha > 0) || !std::isfinite(alpha)) {
      common::ThrowInvalidInput("roughness", ndf_name + " roughness must be a finite number > 0, got " +
                                         std::to_string(alpha),
                        "a perfectly smooth interface is the limit of small roughness, e.g. 1e-3");
    }
  }
}

}  // namespace svbtdf::model
