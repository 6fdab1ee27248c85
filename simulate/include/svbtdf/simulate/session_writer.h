#pragma once
// Writing a simulated capture as a real capture session (docs/session-format.md) and its ground
// truth (docs/truth-format.md): the glue behind `svbtdf simulate`.

#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>

#include "svbtdf/simulate/capture_simulator.h"
#include "svbtdf/simulate/presets.h"
#include "svbtdf/simulate/truth_material.h"
#include "svbtdf/common/image_io.h"
#include "svbtdf/model/dual_microfacet.h"
#include "svbtdf/model/ndf.h"
#include <memory>

namespace svbtdf {

struct SimulationOptions {
  std::string preset = "tiny";
  uint64_t seed = 1;
  double eta = 0.0;          // > 0 overrides the preset's eta
  std::string truth = "model";  // model | montecarlo
  int threads = 0;
  bool progress = true;
  bool noise = true;  // false: no shot or read noise (quantisation stays), for accuracy checks
  // The screen's pose (MonitorConfig) instead of the preset's; NaN: the preset's.
  double monitor_orientation_deg = std::numeric_limits<double>::quiet_NaN();
  double monitor_tilt_deg = std::numeric_limits<double>::quiet_NaN();
  bool mirror_monitor = false;  // a mirrored display, which calibration must refuse (tests)
};

struct SimulationOutput {
  std::filesystem::path session;  // OUT/session
  std::filesystem::path truth;    // OUT/truth
  int64_t images = 0;             // images in the session
  int64_t resumed = 0;            // of which were already there
};

// Simulates the preset into OUT/session and OUT/truth. A folder holding an unfinished simulation
// of the same settings is resumed; any other non-empty OUT is refused (svbtdf::Error(kIo)), and a
// complete session is never touched again.
SimulationOutput SimulateSession(const std::filesystem::path& out, const SimulationOptions& options);

// The ground-truth material of OUT/truth as the simulator wrote it (docs/truth-format.md).
struct MaterialTruth {
  double eta = 1.5;
  std::string ndf_name = "ggx";
  FloatImage ndf_params;  // 5 channels: alpha_x, alpha_y, theta_x, theta_y, theta_z
  FloatImage alpha, shadowing_roughness, k_s, rho_d;
  int width() const { return alpha.width; }
  int height() const { return alpha.height; }
  // The texel's parameters and NDF, as the renderer used them.
  DualMicrofacetParams Params(int x, int y) const;
  std::unique_ptr<Ndf> TexelNdf(int x, int y) const;
  // The same material as the renderer's SpatialBtdf (texel index = y * width + x).
  TruthMaterial ToTruthMaterial() const;
};
// Throws svbtdf::Error naming the file for anything missing or malformed.
MaterialTruth ReadMaterialTruth(const std::filesystem::path& truth_folder);


}  // namespace svbtdf
