#pragma once
// Reading and writing the simulator's ground truth, DIR/truth/ (docs/truth-format.md):
//   rig.json       the true camera (keys camera.fx ... camera.rms_px as calibration writes them),
//                  its pose, the monitor, the dots in 3-D, the board poses, the sensor
//   material.json  the manifest of the ground-truth material (maps and their channels)
// `svbtdf compare` and the calibration tests read these with the functions below.

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "svbtdf/common/image_io.h"
#include "svbtdf/model/dual_microfacet.h"
#include "svbtdf/model/ndf.h"
#include "svbtdf/simulate/renderer.h"
#include "svbtdf/simulate/rig.h"
#include "svbtdf/simulate/truth_material.h"

namespace svbtdf::simulate {

inline constexpr int kTruthFormatVersion = 1;  // material.json of the analytic truth
// rig.json; 2: the Zhang views are whole-sensor images (camera.sensor), the holder board is its own;
// 3: the monitor is a physical screen with a pose (monitor.frame), the dots run along its axes.
inline constexpr int kRigTruthVersion = 3;

// What the capture did besides the rig itself: the exposures used and where the boards were.
struct CaptureTruth {
  std::vector<double> dot_exposures_s;
  std::vector<BoardPose> zhang_boards;
  BoardPose holder_board;
  double all_dots_exposure_s = 0;
  double flat_exposure_s = 0;
  double board_exposure_s = 0;
  uint64_t seed = 0;
  std::string preset;
  std::string pattern;  // the analytic truth's pattern (TruthMaterial::FromPattern); empty: the preset's
  std::string truth_kind = "model";  // model | montecarlo
};

// The truth as read back.
struct RigTruth {
  int version = 0;
  CameraIntrinsics camera;
  double rms_px = 0.0;
  CameraPose pose;
  MonitorConfig monitor;
  SampleConfig sample;
  std::vector<Dot> dots;
  CaptureTruth capture;
};

// Writes DIR/truth/rig.json atomically, never overwriting an existing file.
void WriteRigTruth(const std::filesystem::path& path, const Rig& rig, const CaptureTruth& capture);

// Throws svbtdf::Error(kFormat/kIo) naming the file for a missing file, a wrong version or a
// missing key.
RigTruth ReadRigTruth(const std::filesystem::path& path);

// The analytic ground-truth material, DIR/truth/material.json and its EXR maps, as written.
struct MaterialTruth {
  double eta = 1.5;
  std::string ndf_name = "ggx";
  common::FloatImage ndf_params;  // 5 channels: alpha_x, alpha_y, theta_x, theta_y, theta_z
  common::FloatImage alpha, shadowing_roughness, k_s, rho_d;
  int width() const { return alpha.width; }
  int height() const { return alpha.height; }
  // The texel's parameters and NDF, as the renderer used them.
  model::DualMicrofacetParams Params(int x, int y) const;
  std::unique_ptr<model::Ndf> TexelNdf(int x, int y) const;
  // The same material as the renderer's SpatialBtdf (texel index = y * width + x).
  TruthMaterial ToTruthMaterial() const;
};

// Writes `material` as DIR/material.json plus its maps (atomically; never overwrites).
void WriteMaterialTruth(const std::filesystem::path& folder, const TruthMaterial& material);
// Throws svbtdf::Error naming the file for anything missing or malformed.
MaterialTruth ReadMaterialTruth(const std::filesystem::path& truth_folder);

}  // namespace svbtdf::simulate
