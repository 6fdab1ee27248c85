#include "svbtdf/model/shadowing.h"

#include <cmath>
#include <string>

#include "svbtdf/common/error.h"

namespace svbtdf::model {

SmithShadowing SmithShadowing::Ggx(double roughness) {
  if (!(roughness > 0) || !std::isfinite(roughness)) {
    common::ThrowInvalidInput("shadowing roughness", "must be a finite number > 0, got " + std::to_string(roughness),
                      "use no shadowing instead of a zero roughness");
  }
  return SmithShadowing(roughness);
}

double SmithShadowing::G1(const Vec3& v, const Vec3& h) const {
  const Vec3 side_adjusted = v.z() < 0 ? Vec3(-v) : v;
  const double cos_vh = side_adjusted.dot(h);
  const double cos_v = side_adjusted.z();
  if (cos_vh <= 0 || cos_v <= 0) return 0.0;
  if (!enabled()) return 1.0;
  const double tan2 = std::max(0.0, 1.0 - cos_v * cos_v) / (cos_v * cos_v);
  return 2.0 / (1.0 + std::sqrt(1.0 + roughness_ * roughness_ * tan2));
}

}  // namespace svbtdf::model
