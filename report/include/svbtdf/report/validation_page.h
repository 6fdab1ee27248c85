#pragma once
// What `svbtdf validate-model` shows of the dual-microfacet model against the Monte Carlo slab
// (the paper's Figs. 3 and 5, docs/validation.md): the printed table of relative L2 errors, the
// --json document, and the --plots page (plane-of-incidence cross-sections and index.html).

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "svbtdf/model/hemicube.h"
#include "svbtdf/simulate/model_validation.h"

namespace svbtdf::report {

// How the cases were run, recorded in the JSON and on the page.
struct ValidationSettings {
  std::string ndf;
  double roughness = 0, eta = 0;
  int64_t samples = 0;  // Monte Carlo paths per case
  uint64_t seed = 0;
  int resolution = 0;  // hemicube top-face cells per side
  int max_bounces = 0;
};

// One line per case: config, angle, best alpha, each model's error, MC noise and paths.
std::string ValidationTable(const std::vector<simulate::ValidationCase>& cases);

// {"options": settings, "cases": [...]}: every error, the fitted parameters and the Monte Carlo
// run's statistics of each case.
nlohmann::json ValidationJson(const std::vector<simulate::ValidationCase>& cases, const ValidationSettings& settings);

// Writes one cross-section PNG per case and index.html into `folder`, which must exist; never
// overwrites a file. `grid` is the hemicube the cases were tabulated on.
void WriteValidationPage(const std::vector<simulate::ValidationCase>& cases, const ValidationSettings& settings,
                         const model::Hemicube& grid, const std::filesystem::path& folder);

}  // namespace svbtdf::report
