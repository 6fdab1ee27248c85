#pragma once
// Construction of the analytic NDFs by name, for the command line, the simulator's material
// descriptions and the tests.

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "svbtdf/model/ndf.h"

namespace svbtdf::model {

// The union of the analytic NDFs' parameters; each NDF reads the ones it needs.
struct AnalyticNdfParams {
  double alpha_x = 0.2;  // ggx, beckmann, ellipsoid: roughness along x (the GGX/Beckmann alpha)
  double alpha_y = 0.2;  // ... along y
  double theta_x = 0.0;  // ellipsoid: rotation angles of R = Rx Ry Rz (radians); theta_x and
  double theta_y = 0.0;  //   theta_y skew the lobe off the normal, theta_z rotates it in the plane
  double theta_z = 0.0;
  double kappa = 50.0;   // vmf: concentration
  Vec3 mean = Vec3::UnitZ();  // vmf: mean normal (normalised; must have z > 0)
};

// Names accepted by MakeAnalyticNdf.
std::vector<std::string> AnalyticNdfNames();

// Throws svbtdf::Error(kInvalidInput) for an unknown name or bad parameters, naming them.
std::unique_ptr<Ndf> MakeAnalyticNdf(std::string_view name, const AnalyticNdfParams& params);

}  // namespace svbtdf::model
