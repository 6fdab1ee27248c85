#pragma once
// The HTML report of a fitted material (`svbtdf report`): its quality warnings first, the
// compare metrics when given, its maps and its representatives' NDFs, each beside the ground
// truth's when a truth is given (either kind: a Monte Carlo truth shows its rho_d and its layout
// of slab materials, since it has no alpha or NDF), then the material's provenance.

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
};

// Writes OUT/index.html and its PNG figures; returns the quality warnings shown at the top.
// Throws svbtdf::Error naming the file for a non-empty OUT, an unreadable material or truth, or a
// truth of another size than the material.
std::vector<fit::QualityWarning> WriteMaterialReport(const MaterialReportOptions& options);

}  // namespace svbtdf::report
