// svbtdf render: path-traces a fitted material or a simulator truth in the background or the
// environment scene (docs/render.md) and writes linear EXR, a tone-mapped PNG and, against a
// reference rendering, the image error. With --parametric, a fitted material's texels carry the
// GGX lobes `svbtdf export` fits instead of their tables (docs/export.md).

#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "commands.h"
#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/export/lobe_fit.h"
#include "svbtdf/fit/material.h"
#include "svbtdf/render/image_metrics.h"
#include "svbtdf/render/renderer.h"
#include "svbtdf/render/scene.h"
#include "svbtdf/render/surface.h"

namespace svbtdf::cli {
namespace {
namespace fs = std::filesystem;

struct RenderCommandOptions {
  std::string material, out, png, scene = "background";
  std::vector<double> view_deg = {0.0, 0.0}, resolution = {512, 512}, sample_size;
  render::RenderOptions render;
  render::SceneOptions scene_options;
  std::string background, environment, compare_to, json;
  double exposure = 1.0;
  bool parametric = false;
};

// A fitted material with every texel's NDF replaced by the GGX lobe `svbtdf export` fits
// (--parametric): the material and its lobes, kept alive with the surface drawn on them.
struct ParametricMaterial {
  std::unique_ptr<fit::Material> material;
  std::unique_ptr<render::LobeSurface> surface;
};

ParametricMaterial LoadParametric(const fs::path& folder, std::optional<std::pair<double, double>> sample_size, int threads) {
  if (!fs::is_regular_file(folder / "material.json")) {
    common::ThrowInvalidInput(folder.string(), "is not a fitted material (--parametric renders a material's GGX lobes)");
  }
  ParametricMaterial loaded{std::make_unique<fit::Material>(fit::ReadMaterial(folder)), nullptr};
  const fit::Material& m = *loaded.material;
  exporter::MaterialLobes lobes = exporter::FitMaterialLobes(m, threads, (folder / "material.json").string());
  const auto [width_m, height_m] = sample_size.value_or(std::pair{m.width_m, m.height_m});
  loaded.surface = std::make_unique<render::LobeSurface>(m, std::move(lobes.alpha_x), std::move(lobes.alpha_y),
                                                         std::move(lobes.azimuth), width_m, height_m,
                                                         (folder / "material.json").string());
  return loaded;
}

void RequireWritableFolderOf(const fs::path& file, const char* flag) {
  const fs::path parent = file.has_parent_path() ? file.parent_path() : fs::path(".");
  if (!fs::is_directory(parent)) common::ThrowInvalidInput(flag, "names a file in " + parent.string() + ", which is not a folder");
}

void RunRender(RenderCommandOptions options) {
  if (fs::path(options.out).extension() != ".exr") common::ThrowInvalidInput("--out", "must name an .exr file");
  RequireWritableFolderOf(options.out, "--out");
  if (!options.png.empty()) RequireWritableFolderOf(options.png, "--png");
  options.render.camera.theta_deg = options.view_deg.at(0);
  options.render.camera.phi_deg = options.view_deg.at(1);
  options.render.camera.width = static_cast<int>(options.resolution.at(0));
  options.render.camera.height = static_cast<int>(options.resolution.at(1));
  if (options.resolution[0] != options.render.camera.width || options.resolution[1] != options.render.camera.height) {
    common::ThrowInvalidInput("--resolution", "must be two whole numbers of pixels");
  }
  std::optional<std::pair<double, double>> sample_size;
  if (!options.sample_size.empty()) sample_size = std::pair{options.sample_size.at(0), options.sample_size.at(1)};
  const render::Camera camera(options.render.camera);  // bad views fail before the material is read
  std::optional<common::FloatImage> reference;
  if (!options.compare_to.empty()) reference = common::ReadFloatImage(options.compare_to);

  std::optional<render::LoadedSurface> loaded;
  ParametricMaterial parametric;
  if (options.parametric) {
    parametric = LoadParametric(options.material, sample_size, options.render.threads);
  } else {
    loaded = render::LoadSurface(options.material, sample_size);
  }
  const render::Surface& surface = options.parametric ? *parametric.surface : loaded->surface();
  options.scene_options.scene = options.scene;
  options.scene_options.background = options.background;
  options.scene_options.environment = options.environment;
  const std::unique_ptr<render::Scene> scene = render::MakeScene(options.scene_options, surface.width_m());
  const auto start = std::chrono::steady_clock::now();
  const common::FloatImage image = render::Render(surface, *scene, options.render);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  common::WriteFloatImage(options.out, image, /*half_precision=*/false, /*overwrite=*/true);
  if (!options.png.empty()) {
    common::WriteRgb8Png(options.png, render::ToSrgb8(image, options.exposure), image.width, image.height, /*overwrite=*/true);
  }
  const double samples = static_cast<double>(image.width) * image.height * options.render.samples_per_pixel;
  std::printf("rendered the %s %s (%.4g x %.4g m) in %dx%d at %d spp: %.1f s, %.2f M samples/s -> %s\n",
              surface.description().c_str(), options.material.c_str(), surface.width_m(), surface.height_m(), image.width, image.height, options.render.samples_per_pixel, seconds,
              samples / seconds * 1e-6, options.out.c_str());
  // What was rendered and how, so that a report can show the image and redraw the same view
  // (docs/render.md, "The JSON summary").
  const render::CameraOptions& view = options.render.camera;
  nlohmann::json metrics = {
      {"format", "svbtdf-render"}, {"version", 1}, {"image", options.out}, {"png", options.png},
      {"material", options.material}, {"surface", surface.description()}, {"parametric", options.parametric},
      {"seconds", seconds}, {"samples_per_pixel", options.render.samples_per_pixel}, {"exposure", options.exposure},
      {"camera", {{"theta_deg", view.theta_deg}, {"phi_deg", view.phi_deg}, {"distance_m", view.distance_m},
                  {"fov_deg", view.fov_deg}, {"width", view.width}, {"height", view.height}}},
      {"scene", {{"scene", options.scene_options.scene}, {"background", options.scene_options.background.string()},
                 {"environment", options.scene_options.environment.string()},
                 {"background_distance_m", options.scene_options.background_distance_m},
                 {"background_width_m", options.scene_options.background_width_m},
                 {"checker_size_m", options.scene_options.checker_size_m}}},
      {"sample", {{"width_m", surface.width_m()}, {"height_m", surface.height_m()}}}};
  if (reference) {
    try {
      metrics["relative_rmse"] = render::RelativeRmse(image, *reference);
      metrics["ssim"] = render::Ssim(image, *reference);
    } catch (const common::Error& e) {
      common::ThrowInvalidInput(options.compare_to, e.what());
    }
    metrics["reference"] = options.compare_to;
    std::printf("against %s: relative RMSE %.4f, SSIM %.4f\n", options.compare_to.c_str(),
                metrics["relative_rmse"].get<double>(), metrics["ssim"].get<double>());
  }
  if (!options.json.empty()) common::WriteTextAtomically(options.json, metrics.dump(2) + "\n", /*overwrite=*/true);
}

}  // namespace

void AddRenderCommand(CLI::App& app) {
  auto options = std::make_shared<RenderCommandOptions>();
  CLI::App* command = app.add_subcommand(
      "render", "Path-trace a fitted material or a simulator truth in front of a background or in an environment");
  command->add_option("material", options->material, "material folder (docs/material-format.md) or truth folder (OUT/truth)")
      ->required();
  command->add_option("--out", options->out, "linear RGB OpenEXR to write")->required();
  command->add_option("--png", options->png, "also write a tone-mapped 8-bit sRGB PNG");
  command->add_option("--exposure", options->exposure, "scale before tone mapping the PNG")->capture_default_str();
  command->add_option("--scene", options->scene, "background | environment (docs/render.md)")->capture_default_str();
  command->add_option("--view-deg", options->view_deg, "camera direction from the sample centre: THETA (from the normal) PHI")
      ->expected(2)
      ->capture_default_str();
  command->add_option("--distance", options->render.camera.distance_m, "camera distance from the sample centre (m)")
      ->capture_default_str();
  command->add_option("--fov-deg", options->render.camera.fov_deg, "horizontal field of view (degrees)")->capture_default_str();
  command->add_option("--resolution", options->resolution, "image size W H (pixels)")->expected(2)->capture_default_str();
  command->add_option("--spp", options->render.samples_per_pixel, "samples per pixel")->capture_default_str();
  command->add_option("--seed", options->render.seed, "random seed (same seed, same image)")->capture_default_str();
  command->add_option("--threads", options->render.threads, "worker threads (0: all cores)")->capture_default_str();
  command->add_option("--background", options->background, "background picture (EXR linear; PNG/JPEG sRGB); default: a checkerboard");
  command->add_option("--background-distance", options->scene_options.background_distance_m, "background plane behind the sample (m)")
      ->capture_default_str();
  command->add_option("--background-width", options->scene_options.background_width_m,
                      "physical width of the background picture, repeated over the plane (m; default: twice the sample's)");
  command->add_option("--checker-size", options->scene_options.checker_size_m, "the default checkerboard's square (m)")->capture_default_str();
  command->add_option("--environment", options->environment, "equirectangular EXR environment of --scene environment");
  command->add_option("--sample-size", options->sample_size,
                      "the sample's size W H (m), for a material that does not record it")
      ->expected(2);
  command->add_flag("--parametric", options->parametric,
                    "render a fitted material's GGX lobes (what `svbtdf export` writes) instead of its tables");
  command->add_option("--compare-to", options->compare_to, "reference EXR: print the relative RMSE and SSIM against it");
  command->add_option("--json", options->json, "write the timing and the comparison as JSON");
  command->callback([options] { RunRender(*options); });
}

}  // namespace svbtdf::cli
