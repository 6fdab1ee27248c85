#pragma once
// A fitted material as glTF 2.0 (docs/export.md): a quad of the sample's physical size whose
// material carries every texel's GGX lobe (roughness and KHR_materials_anisotropy), its specular
// fraction (KHR_materials_transmission), eta (KHR_materials_ior), thin walls
// (KHR_materials_volume, thickness 0), rho_d (KHR_materials_diffuse_transmission) and k_s (base
// colour), as PNG textures beside a .gltf and a .bin.

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "svbtdf/export/lobe_fit.h"
#include "svbtdf/fit/material.h"

namespace svbtdf::exporter {

// One texel in glTF's terms (docs/export.md has the derivation).
struct GltfTexel {
  double roughness = 0;        // sqrt(alpha) of the lobe's narrower axis, in [0, 1]
  double anisotropy_strength = 0;  // s: the wider axis's alpha = mix(alpha, 1, s^2)
  double direction_x = 1, direction_y = 0;  // the wider axis in the quad's tangent frame (= sample x, y)
  double transmission = 1;     // the specular fraction of the transmitted energy
  std::array<double, 3> base_color{};                  // linear, k_s / transmission, clamped to 1
  std::array<double, 3> diffuse_transmission_color{};  // linear, pi rho_d / (1 - transmission), clamped to 1
  bool clamped = false;        // an alpha beyond glTF's roughness 1, or a colour beyond 1
};
GltfTexel MapTexel(const GgxLobe& lobe, const std::array<double, 3>& k_s, const std::array<double, 3>& rho_d);

struct GltfFiles {
  std::filesystem::path gltf, summary;           // OUT_DIR/<name>.gltf, OUT_DIR/<name>.export.json
  std::vector<std::filesystem::path> written;     // every file, the .gltf last
};

// Writes OUT_DIR/<name>.gltf, <name>.bin, <name>_*.png, the lobe maps (<name>_lobe_*.exr: alpha_x,
// alpha_y, azimuth, relative error) and <name>.export.json (the mapping's figures, `summary`
// merged in). OUT_DIR is created when missing; files of an earlier export of the same name are
// replaced, each atomically, the .gltf last. Throws svbtdf::Error(kInvalidInput) for a material
// without a physical size.
GltfFiles WriteGltf(const fit::Material& material, const MaterialLobes& lobes, const std::filesystem::path& out_dir,
                    const std::string& name, const nlohmann::json& summary = nlohmann::json::object());

}  // namespace svbtdf::exporter
