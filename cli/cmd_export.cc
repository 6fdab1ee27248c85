// svbtdf export: a fitted material as glTF 2.0 for the renderers people use (docs/export.md):
// every texel's tabulated NDF fitted by an anisotropic GGX lobe, written with the Khronos
// transmission, volume, IOR, anisotropy and diffuse-transmission extensions.

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "commands.h"
#include "svbtdf/common/folder_lock.h"
#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/parallel.h"
#include "svbtdf/export/gltf.h"
#include "svbtdf/export/lobe_fit.h"
#include "svbtdf/fit/material.h"

namespace svbtdf::cli {
namespace {
namespace fs = std::filesystem;

struct ExportCommandOptions {
  std::string material, gltf, name;
  int threads = 0;
};

void RunExport(const ExportCommandOptions& options) {
  const int threads = common::ThreadCount(options.threads);  // a bad --threads fails before the work
  const fs::path folder = common::WithoutTrailingSeparators(options.material);
  if (!fs::is_regular_file(folder / "material.json")) {
    common::ThrowInvalidInput(folder.string(), "is not a material folder (it has no material.json)");
  }
  const fit::Material material = fit::ReadMaterial(folder);
  exporter::RequireLobeFittable(material, (folder / "material.json").string());
  const std::string name = options.name.empty() ? folder.filename().string() : options.name;
  if (name.empty() || name.find('/') != std::string::npos) common::ThrowInvalidInput("--name", "must be a plain file name");

  const common::FolderLock lock = common::FolderLock::Acquire(options.gltf, "svbtdf export");
  const auto start = std::chrono::steady_clock::now();
  const exporter::MaterialLobes lobes = exporter::FitMaterialLobes(material, threads, (folder / "material.json").string());
  const double fit_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  nlohmann::json summary;
  summary["material"] = fs::absolute(folder).string();
  summary["lobe_fit"]["seconds"] = fit_seconds;
  summary["lobe_fit"]["threads"] = threads;
  const exporter::GltfFiles files = exporter::WriteGltf(material, lobes, options.gltf, name, summary);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  const exporter::ErrorDistribution error = exporter::Distribution(lobes.relative_error);
  std::printf("exported %dx%d texels to %s in %.1f s (lobe fit %.1f s); GGX lobe fit relative error: median %.3f, "
              "p90 %.3f, max %.3f%s\n",
              material.width, material.height, files.gltf.string().c_str(), seconds, fit_seconds, error.median,
              error.p90, error.max, lobes.exact ? " (the material's lobes are GGX already)" : "");
}

}  // namespace

void AddExportCommand(CLI::App& app) {
  auto options = std::make_shared<ExportCommandOptions>();
  CLI::App* command = app.add_subcommand("export", "Export a fitted material as glTF 2.0 (docs/export.md)");
  command->add_option("material", options->material, "fitted material folder")->required();
  command->add_option("--gltf", options->gltf, "output folder for NAME.gltf, NAME.bin and the textures")->required();
  command->add_option("--name", options->name, "file name stem (default: the material folder's name)");
  command->add_option("--threads", options->threads, "worker threads (default: all cores)")->capture_default_str();
  command->callback([options] { RunExport(*options); });
}

}  // namespace svbtdf::cli
