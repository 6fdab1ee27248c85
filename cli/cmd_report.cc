// svbtdf report MATERIAL --out DIR [--truth DIR/truth] [--compare FILE]: pictures of a fitted
// material (its maps and NDFs), beside the ground truth (either kind) when there is one, in an
// HTML page written by report/material_report.h.

#include <cstdio>
#include <filesystem>
#include <memory>
#include <vector>

#include "commands.h"
#include "svbtdf/common/folder_lock.h"
#include "svbtdf/report/material_report.h"

namespace svbtdf::cli {
namespace {

void RunReport(const report::MaterialReportOptions& options) {
  const common::FolderLock lock = common::FolderLock::Acquire(options.out, "svbtdf report");
  const std::vector<fit::QualityWarning> warnings = report::WriteMaterialReport(options);
  std::printf("report: %s\n", (options.out / "index.html").c_str());
  if (!warnings.empty()) {
    std::fflush(stdout);
    std::fprintf(stderr, "svbtdf: the report shows %zu quality warning%s at its top\n", warnings.size(),
                 warnings.size() == 1 ? "" : "s");
  }
}

}  // namespace

void AddReportCommand(CLI::App& app) {
  auto options = std::make_shared<report::MaterialReportOptions>();
  CLI::App* report = app.add_subcommand("report", "Pictures of a fitted material (maps, NDFs) in an HTML page");
  report->add_option("material", options->material_folder, "fitted material folder")->required();
  report->add_option("--out", options->out, "new folder for the report")->required();
  report->add_option("--truth", options->truth_folder,
                     "ground truth written by 'svbtdf simulate' (OUT/truth, model or montecarlo), shown alongside");
  report->add_option("--compare", options->compare_file, "metrics written by 'svbtdf compare --json', shown as a table");
  report->add_option("--session", options->session_folder,
                     "capture session (calibration and images); default: the material's provenance");
  report->add_option("--store", options->store_folder, "slice store (measured slices); default: the material's provenance");
  report->add_option("--renders", options->renders_folder, "folder of 'svbtdf render --json' summaries and their PNGs");
  report->add_option("--gltf", options->gltf_file, "the .gltf of 'svbtdf export', shown live with three.js");
  report->add_option("--validation", options->validation_page, "the index.html of 'svbtdf validate-model --plots', linked");
  report->add_option("--inspect-grid", options->inspect_grid, "at most this many clickable texels per side")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  report->add_option("--lobe-grid", options->lobe_grid, "the live view's spherical-Gaussian lobes per side")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  report->add_option("--ndfs", options->max_ndfs, "number of representatives' NDFs to show")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  report->callback([options] { RunReport(*options); });
}

}  // namespace svbtdf::cli
