#pragma once
// Argument checks shared by the NDF constructors, so that every NDF rejects bad parameters with
// the same clear message.

#include <string>

namespace svbtdf::model {

// Throws svbtdf::Error(kInvalidInput) naming `ndf_name` unless both roughnesses are finite and > 0.
void RequirePositiveRoughness(const std::string& ndf_name, double alpha_x, double alpha_y);

}  // namespace svbtdf::model
