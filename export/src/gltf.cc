#include "svbtdf/export/gltf.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numbers>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/image_io.h"
#include "svbtdf/render/image_metrics.h"

namespace svbtdf::exporter {
namespace fs = std::filesystem;
namespace {

using Json = nlohmann::json;

double Mean(const std::array<double, 3>& v) { return (v[0] + v[1] + v[2]) / 3.0; }

// glTF's constants (glTF 2.0 specification, 5.1.2 and 5.26).
constexpr int kFloat = 5126, kUnsignedShort = 5123;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;
constexpr int kLinear = 9729, kClampToEdge = 33071;

// The quad's vertex data, each attribute its own buffer view (no strides to get wrong).
struct QuadBuffer {
  std::string bytes;
  Json buffer_views = Json::array(), accessors = Json::array();

  int Add(const void* data, size_t size, int component, int count, const char* type, int target, Json extra = Json::object()) {
    while (bytes.size() % 4 != 0) bytes.push_back('\0');
    const size_t offset = bytes.size();
    bytes.append(static_cast<const char*>(data), size);
    buffer_views.push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", size}, {"target", target}});
    Json accessor = {{"bufferView", buffer_views.size() - 1}, {"componentType", component}, {"count", count}, {"type", type}};
    accessor.update(extra);
    accessors.push_back(accessor);
    return static_cast<int>(accessors.size()) - 1;
  }
};

// The sample as a quad in glTF's x-y plane, normal +z (the camera's side, docs/model.md's z),
// texel row 0 at the +y edge (docs/slice-store.md) where glTF's v = 0 (the image's first row).
Json QuadMesh(const fit::Material& material, QuadBuffer& buffer) {
  const float w = static_cast<float>(material.width_m / 2), h = static_cast<float>(material.height_m / 2);
  const float positions[] = {-w, -h, 0, w, -h, 0, w, h, 0, -w, h, 0};
  const float normals[] = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
  // Bitangent = normal x tangent * w = +y: KHR_materials_anisotropy's directions are in (x, y).
  const float tangents[] = {1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1};
  const float uvs[] = {0, 1, 1, 1, 1, 0, 0, 0};
  const uint16_t indices[] = {0, 1, 2, 0, 2, 3};
  Json attributes;
  attributes["POSITION"] = buffer.Add(positions, sizeof positions, kFloat, 4, "VEC3", kArrayBuffer,
                                      {{"min", {-w, -h, 0}}, {"max", {w, h, 0}}});
  attributes["NORMAL"] = buffer.Add(normals, sizeof normals, kFloat, 4, "VEC3", kArrayBuffer);
  attributes["TANGENT"] = buffer.Add(tangents, sizeof tangents, kFloat, 4, "VEC4", kArrayBuffer);
  attributes["TEXCOORD_0"] = buffer.Add(uvs, sizeof uvs, kFloat, 4, "VEC2", kArrayBuffer);
  const int index_accessor = buffer.Add(indices, sizeof indices, kUnsignedShort, 6, "SCALAR", kElementArrayBuffer);
  return {{"name", "sample"}, {"primitives", {{{"attributes", attributes}, {"indices", index_accessor}, {"material", 0}}}}};
}

// Maps of every texel's glTF values, as 8-bit RGB (linear data; colours sRGB-encoded).
struct TextureMaps {
  common::FloatImage base_color, diffuse_color;  // linear RGB, encoded to sRGB on writing
  std::vector<uint8_t> metallic_roughness, transmission, anisotropy;  // linear RGB bytes
  int64_t clamped_texels = 0;
};

uint8_t Linear8(double value) { return static_cast<uint8_t>(std::lround(255.0 * std::clamp(value, 0.0, 1.0))); }

TextureMaps MapTexels(const fit::Material& material, const MaterialLobes& lobes) {
  const int width = material.width, height = material.height;
  const size_t bytes = static_cast<size_t>(width) * height * 3;
  TextureMaps maps{common::FloatImage(width, height, 3), common::FloatImage(width, height, 3),
                   std::vector<uint8_t>(bytes), std::vector<uint8_t>(bytes), std::vector<uint8_t>(bytes), 0};
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      std::array<double, 3> k_s{}, rho_d{};
      for (int c = 0; c < 3; ++c) k_s[c] = material.k_s.at(x, y, c), rho_d[c] = material.rho_d.at(x, y, c);
      const GltfTexel texel = MapTexel({lobes.alpha_x.at(x, y), lobes.alpha_y.at(x, y), lobes.azimuth.at(x, y)}, k_s, rho_d);
      maps.clamped_texels += texel.clamped;
      const size_t i = (static_cast<size_t>(y) * width + x) * 3;
      for (int c = 0; c < 3; ++c) {
        maps.base_color.at(x, y, c) = static_cast<float>(texel.base_color[c]);
        maps.diffuse_color.at(x, y, c) = static_cast<float>(texel.diffuse_transmission_color[c]);
        maps.transmission[i + c] = Linear8(texel.transmission);  // glTF reads R
      }
      // metallicRoughness: G roughness, B metalness (0), R unused.
      maps.metallic_roughness[i + 1] = Linear8(texel.roughness);
      maps.anisotropy[i + 0] = Linear8(0.5 * (texel.direction_x + 1));
      maps.anisotropy[i + 1] = Linear8(0.5 * (texel.direction_y + 1));
      maps.anisotropy[i + 2] = Linear8(texel.anisotropy_strength);
    }
  }
  return maps;
}

Json TextureInfo(int index) { return {{"index", index}}; }

Json MaterialJson(const fit::Material& material, const std::string& name) {
  // Texture indices follow the order of the images written in WriteGltf.
  Json extensions;
  extensions["KHR_materials_transmission"] = {{"transmissionFactor", 1.0}, {"transmissionTexture", TextureInfo(2)}};
  extensions["KHR_materials_volume"] = {{"thicknessFactor", 0.0}};  // thin-walled, as the model's slab
  extensions["KHR_materials_ior"] = {{"ior", material.eta}};
  extensions["KHR_materials_anisotropy"] = {{"anisotropyStrength", 1.0}, {"anisotropyTexture", TextureInfo(3)}};
  extensions["KHR_materials_diffuse_transmission"] = {{"diffuseTransmissionFactor", 1.0},
                                                      {"diffuseTransmissionColorTexture", TextureInfo(4)}};
  return {{"name", name},
          {"doubleSided", true},
          {"pbrMetallicRoughness",
           {{"baseColorTexture", TextureInfo(0)}, {"metallicFactor", 0.0}, {"roughnessFactor", 1.0},
            {"metallicRoughnessTexture", TextureInfo(1)}}},
          {"extensions", extensions}};
}

void WriteExr(const fs::path& path, const common::FloatImage& image, std::vector<fs::path>& written) {
  common::WriteFloatImage(path, image, /*half_precision=*/false, /*overwrite=*/true);
  written.push_back(path);
}

}  // namespace

GltfTexel MapTexel(const GgxLobe& lobe, const std::array<double, 3>& k_s, const std::array<double, 3>& rho_d) {
  GltfTexel texel;
  // KHR_materials_anisotropy: alpha_t = mix(alpha, 1, s^2) along the direction, alpha_b = alpha
  // across it, alpha = roughness^2. So the narrower axis gives the roughness, the wider the strength.
  const bool x_wider = lobe.alpha_x >= lobe.alpha_y;
  const double wide = std::max(lobe.alpha_x, lobe.alpha_y), narrow = std::min(lobe.alpha_x, lobe.alpha_y);
  const double alpha = std::min(narrow, 1.0), alpha_t = std::clamp(wide, alpha, 1.0);
  texel.clamped = wide > 1.0;
  texel.roughness = std::sqrt(alpha);
  texel.anisotropy_strength = alpha < 1.0 ? std::sqrt((alpha_t - alpha) / (1.0 - alpha)) : 0.0;
  const double direction = lobe.azimuth + (x_wider ? 0.0 : std::numbers::pi / 2);
  texel.direction_x = std::cos(direction), texel.direction_y = std::sin(direction);
  // Transmitted energy at normal incidence: about k_s through the lobe (its NDF is normalised) and
  // pi rho_d through the Lambertian part. glTF splits transmission T between its specular BTDF
  // (weight T, tinted by the base colour) and the diffuse BTDF (weight 1 - T, tinted by the
  // diffuse transmission colour), so T is the specular fraction and each tint is its energy over
  // its weight.
  std::array<double, 3> diffuse{};
  for (int c = 0; c < 3; ++c) diffuse[c] = std::numbers::pi * std::max(rho_d[c], 0.0);
  std::array<double, 3> specular{};
  for (int c = 0; c < 3; ++c) specular[c] = std::max(k_s[c], 0.0);
  const double total = Mean(specular) + Mean(diffuse);
  texel.transmission = total > 0 ? Mean(specular) / total : 1.0;
  for (int c = 0; c < 3; ++c) {
    const double base = texel.transmission > 0 ? specular[c] / texel.transmission : 1.0;
    const double tint = texel.transmission < 1 ? diffuse[c] / (1.0 - texel.transmission) : 0.0;
    texel.clamped = texel.clamped || base > 1.0 || tint > 1.0;
    texel.base_color[c] = std::min(base, 1.0);
    texel.diffuse_transmission_color[c] = std::min(tint, 1.0);
  }
  return texel;
}

GltfFiles WriteGltf(const fit::Material& material, const MaterialLobes& lobes, const fs::path& out_dir,
                    const std::string& name, const Json& summary) {
  if (!(material.width_m > 0 && material.height_m > 0)) {
    common::ThrowInvalidInput("material.json", "records no sample size (\"sample\": width_m, height_m), which the quad needs");
  }
  fs::create_directories(out_dir);
  GltfFiles files;
  const TextureMaps maps = MapTexels(material, lobes);
  const int w = material.width, h = material.height;
  // The order fixes the texture indices MaterialJson uses.
  const std::vector<std::pair<std::string, std::vector<uint8_t>>> images = {
      {"base_color", render::ToSrgb8(maps.base_color)},
      {"metallic_roughness", maps.metallic_roughness},
      {"transmission", maps.transmission},
      {"anisotropy", maps.anisotropy},
      {"diffuse_transmission_color", render::ToSrgb8(maps.diffuse_color)}};
  Json gltf_images = Json::array(), textures = Json::array();
  for (const auto& [role, pixels] : images) {
    const std::string file = name + "_" + role + ".png";
    common::WriteRgb8Png(out_dir / file, pixels, w, h, /*overwrite=*/true);
    files.written.push_back(out_dir / file);
    gltf_images.push_back({{"uri", file}, {"mimeType", "image/png"}, {"name", role}});
    textures.push_back({{"source", gltf_images.size() - 1}, {"sampler", 0}});
  }
  WriteExr(out_dir / (name + "_lobe_alpha_x.exr"), lobes.alpha_x, files.written);
  WriteExr(out_dir / (name + "_lobe_alpha_y.exr"), lobes.alpha_y, files.written);
  WriteExr(out_dir / (name + "_lobe_azimuth.exr"), lobes.azimuth, files.written);
  WriteExr(out_dir / (name + "_lobe_error.exr"), lobes.relative_error, files.written);

  QuadBuffer buffer;
  const Json mesh = QuadMesh(material, buffer);
  const std::string bin = name + ".bin";
  common::WriteTextAtomically(out_dir / bin, buffer.bytes);
  files.written.push_back(out_dir / bin);

  const std::vector<std::string> used = {"KHR_materials_transmission", "KHR_materials_volume", "KHR_materials_ior",
                                         "KHR_materials_anisotropy", "KHR_materials_diffuse_transmission"};
  Json gltf = {
      {"asset", {{"version", "2.0"}, {"generator", "svbtdf export (docs/export.md)"}}},
      {"extensionsUsed", used},
      {"scene", 0},
      {"scenes", {{{"name", name}, {"nodes", {0}}}}},
      {"nodes", {{{"name", name}, {"mesh", 0}}}},
      {"meshes", {mesh}},
      {"materials", {MaterialJson(material, name)}},
      {"textures", textures},
      {"images", gltf_images},
      {"samplers", {{{"magFilter", kLinear}, {"minFilter", kLinear}, {"wrapS", kClampToEdge}, {"wrapT", kClampToEdge}}}},
      {"buffers", {{{"uri", bin}, {"byteLength", buffer.bytes.size()}}}},
      {"bufferViews", buffer.buffer_views},
      {"accessors", buffer.accessors}};

  Json report = summary;
  const ErrorDistribution error = Distribution(lobes.relative_error);
  report["format"] = "svbtdf-export";
  report["gltf"] = name + ".gltf";
  report["texels"] = static_cast<int64_t>(w) * h;
  report["lobe_fit"]["relative_error"] = {{"median", error.median}, {"p90", error.p90}, {"max", error.max},
                                          {"map", name + "_lobe_error.exr"}};
  report["lobe_fit"]["exact"] = lobes.exact;
  report["clamped_texels"] = maps.clamped_texels;
  report["not_carried"] = {"the blend weight alpha between the two configurations", "the shadowing roughness",
                           "the tabulated lobe's shape beyond an ellipse (lobe_fit.relative_error)"};
  if (material.internal_reflection) {
    report["not_carried"].push_back("the light reflected inside the slab (material format version 4)");
  }
  files.summary = out_dir / (name + ".export.json");
  common::WriteTextAtomically(files.summary, report.dump(2) + "\n");
  files.written.push_back(files.summary);
  // The .gltf last: a reader that finds it finds everything it names.
  files.gltf = out_dir / (name + ".gltf");
  common::WriteTextAtomically(files.gltf, gltf.dump(2) + "\n");
  files.written.push_back(files.gltf);
  return files;
}

}  // namespace svbtdf::exporter
