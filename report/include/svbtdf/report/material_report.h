#pragma once
// The HTML report of a fitted material (`svbtdf report`): its quality warnings first, the
// compare metrics when given, its maps and its representatives' NDFs, each beside the ground
// truth's when a truth is given (either kind: a Monte Carlo truth shows its rho_d and its layout
// of slab materials, since it has no alpha or NDF), then the material's provenance.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "svbtdf/fit/quality.h"

namespace svbtdf::report {

struct MaterialReportOptions {
  std::string material_folder;  // as the user spelled it: shown on the page
  std::filesystem::path out;    // a new or empty folder: OUT/index.html and its figures
  std::string truth_folder;     // DIR/truth of `svbtdf simulate`, either kind; empty: none
  std::string compare_file;     // metrics of `svbtdf compare --json`, shown as a table; empty: none
  int max_ndfs = 12;            // representatives' NDFs shown
  // What the interactive page shows besides the maps (docs/report.md); each optional.
  std::string session_folder;   // the capture (calibration.json, images); empty: the material's provenance.session
  std::string store_folder;     // the slice store (measured slices); empty: the material's provenance.processed
  std::string renders_folder;   // `svbtdf render --json` summaries and their PNGs; empty: none
  std::string gltf_file;        // `svbtdf export`'s .gltf, shown live and embedded; empty: none
  std::string validation_page;  // `svbtdf validate-model --plots DIR`'s DIR/index.html, linked; empty: none
  int inspect_grid = 64;        // at most this many texels per side can be clicked for their slice
  int64_t inspect_budget = 400000;  // grid texels x dots at most (the page's size)
  int lobe_grid = 64;           // the live spherical-Gaussian view's lobes per side
  std::filesystem::path assets; // the page's scripts (report.js, three-bundle.js); empty: ReportAssetsFolder()
  int threads = 0;              // 0: every core
};

// Where the page's scripts are: $SVBTDF_REPORT_ASSETS, else the source tree's report/assets with
// tools/report/dist (three.js bundled by scripts/install-deps.sh).
std::vector<std::filesystem::path> ReportAssetFiles(const std::filesystem::path& assets);

// Writes OUT/index.html and its PNG figures; returns the quality warnings shown at the top.
// Throws svbtdf::Error naming the file for a non-empty OUT, an unreadable material or truth, or a
// truth of another size than the material.
std::vector<fit::QualityWarning> WriteMaterialReport(const MaterialReportOptions& options);

}  // namespace svbtdf::report
