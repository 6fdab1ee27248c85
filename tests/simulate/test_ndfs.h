#pragma once
// NDFs shared by the simulate tests.
#include <memory>

#include "dev_ggx.h"  // TEMPORARY until ndf_factory.h lands

namespace svbtdf {

inline std::unique_ptr<Ndf> RoughNdf(double roughness) { return std::make_unique<DevGgx>(roughness); }

// TEMPORARY: will be the skewed, rotated Ellipsoid NDF.
inline std::unique_ptr<Ndf> SkewedNdf() { return std::make_unique<DevGgx>(0.25); }

}  // namespace svbtdf

namespace svbtdf {
// TEMPORARY: will be Beckmann (the paper's Gaussian NDF).
inline std::unique_ptr<Ndf> PaperNdf(double roughness) { return std::make_unique<DevBeckmann>(roughness); }
}  // namespace svbtdf
