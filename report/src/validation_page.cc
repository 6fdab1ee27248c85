#include "svbtdf/report/validation_page.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <sstream>
#include <utility>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/report/line_plot.h"

namespace svbtdf::report {
namespace {
namespace fs = std::filesystem;

// One model's curve in a plot and its column in the tables.
struct ModelColumn {
  const char* key;
  const char* label;
  Rgb8 color;
  const std::vector<double> simulate::ValidationCase::*values;
  double simulate::ModelErrors::*error;
};

const ModelColumn kColumns[] = {
    {"rho_T", "rho_T (rough entry)", {31, 119, 180}, &simulate::ValidationCase::rho_T, &simulate::ModelErrors::rho_T},
    {"rho_B", "rho_B (rough exit)", {214, 39, 40}, &simulate::ValidationCase::rho_B, &simulate::ModelErrors::rho_B},
    {"blend", "blend, best alpha", {44, 160, 44}, &simulate::ValidationCase::blend, &simulate::ModelErrors::blend},
    {"single_same_ndf", "single interface, same NDF", {255, 127, 14}, &simulate::ValidationCase::single_same_ndf,
     &simulate::ModelErrors::single_same_ndf},
    {"single_fitted", "single interface, fitted roughness", {148, 103, 189},
     &simulate::ValidationCase::single_fitted, &simulate::ModelErrors::single_fitted},
    {"blend_fitted", "blend, fitted alpha and roughness", {23, 190, 207}, &simulate::ValidationCase::blend_fitted,
     &simulate::ModelErrors::blend_fitted},
    {"slab_lobe", "slab lobe (seed 000, vMF)", {140, 86, 75}, &simulate::ValidationCase::slab_lobe,
     &simulate::ModelErrors::slab_lobe},
    {"blend_internal", "blend + internal reflection", {227, 119, 194}, &simulate::ValidationCase::blend_internal,
     &simulate::ModelErrors::blend_internal},
    {"blend_internal_fitted", "blend + internal reflection, fitted", {188, 189, 34},
     &simulate::ValidationCase::blend_internal_fitted, &simulate::ModelErrors::blend_internal_fitted},
    {"two_interfaces", "two interfaces, exact (no internal reflection)", {150, 150, 150},
     &simulate::ValidationCase::two_interfaces, &simulate::ModelErrors::two_interfaces},
    {"two_interfaces_internal", "two interfaces + internal reflection, fitted weight", {0, 60, 150},
     &simulate::ValidationCase::two_interfaces_internal, &simulate::ModelErrors::two_interfaces_internal},
    {"two_interfaces_internal_longer", "two interfaces + internal reflection + longer paths, fitted weights",
     {230, 171, 2}, &simulate::ValidationCase::two_interfaces_internal_longer,
     &simulate::ModelErrors::two_interfaces_internal_longer},
};

nlohmann::json ErrorsToJson(const simulate::ModelErrors& errors) {
  nlohmann::json out;
  for (const ModelColumn& column : kColumns) out[column.key] = errors.*column.error;
  return out;
}

nlohmann::json CaseToJson(const simulate::ValidationCase& c) {
  const simulate::EnergyFractions& f = c.mc.fractions;
  return {
      {"config", ToString(c.rough_sides)},
      {"incidence_deg", c.incidence_deg},
      {"best_alpha", c.best_alpha},
      {"error", ErrorsToJson(c.errors)},
      {"scale_free_error", ErrorsToJson(c.scale_free_errors)},
      {"fitted_roughness", c.fitted_roughness},
      {"blend_fitted", {{"alpha", c.blend_fitted_alpha}, {"roughness", c.blend_fitted_roughness}}},
      {"slab_lobe", {{"ndf_kappa", c.slab_lobe_ndf_kappa}, {"light_kappa", c.slab_lobe_light_kappa}}},
      {"blend_internal", {{"alpha", c.best_alpha_internal}}},
      {"blend_internal_fitted",
       {{"alpha", c.blend_internal_fitted_alpha}, {"roughness", c.blend_internal_fitted_roughness}}},
      {"two_interfaces_internal", {{"weight", c.two_interfaces_internal_weight}}},
      {"two_interfaces_internal_longer",
       {{"internal_weight", c.longer_internal_weight}, {"longer_weight", c.longer_longer_weight}}},
      {"view_direction", {c.o.x(), c.o.y(), c.o.z()}},
      {"monte_carlo",
       {{"paths", c.mc.paths},
        {"seconds", c.mc.seconds},
        {"noise_relative_l2", c.mc_noise},
        {"dominant_relative_error_90", c.mc.DominantRelativeError(0.9)},
        {"fractions",
         {{"transmitted", f.transmitted},
          {"reflected", f.reflected},
          {"absorbed", f.absorbed},
          {"masked", f.masked},
          {"capped", f.capped}}}}},
  };
}

// The slice along the plane of incidence (y = 0): the cells on both sides of the plane, averaged,
// in order of the signed angle s of the light direction i = (sin s, 0, -cos s) from -z.
struct CrossSection {
  std::vector<double> angles_deg;
  std::vector<std::pair<int, int>> cells;
};

CrossSection PlaneOfIncidence(const model::Hemicube& grid) {
  CrossSection section;
  constexpr double kStepDeg = 0.05;
  constexpr double kOffset = 1e-9;  // selects the cells just above and below y = 0
  double angle_sum = 0.0;
  int count = 0;
  for (double s = -89.9; s <= 89.9; s += kStepDeg) {
    const double r = s * model::kPi / 180.0;
    const std::pair<int, int> cells = {grid.CellOf(model::Vec3(std::sin(r), kOffset, std::cos(r)).normalized()),
                                       grid.CellOf(model::Vec3(std::sin(r), -kOffset, std::cos(r)).normalized())};
    if (section.cells.empty() || cells != section.cells.back()) {
      if (count > 0) section.angles_deg.push_back(angle_sum / count);
      section.cells.push_back(cells);
      angle_sum = 0.0;
      count = 0;
    }
    angle_sum += s;
    ++count;
  }
  section.angles_deg.push_back(angle_sum / count);
  return section;
}

std::vector<double> Along(const CrossSection& section, const std::vector<double>& values) {
  std::vector<double> out;
  for (const auto& [a, b] : section.cells) out.push_back(0.5 * (values[a] + values[b]));
  return out;
}

std::string PlotName(const simulate::ValidationCase& c) {
  return std::string(ToString(c.rough_sides)) + "_" + std::to_string(std::lround(c.incidence_deg)) + ".png";
}

void WritePlot(const simulate::ValidationCase& c, const CrossSection& section, const fs::path& path) {
  LinePlot plot;
  for (const ModelColumn& column : kColumns) {
    if ((c.*column.values).empty()) continue;  // a column that was not computed
    PlotSeries series;
    series.name = column.label;
    series.color = column.color;
    series.x = section.angles_deg;
    series.y = Along(section, c.*column.values);
    plot.series.push_back(std::move(series));
  }
  PlotSeries mc;
  mc.name = "Monte Carlo (2 standard errors)";
  mc.line_width = 0.0;
  mc.x = section.angles_deg;
  mc.y = Along(section, c.mc.rho);
  for (const auto& [a, b] : section.cells) {
    mc.error.push_back(2.0 * 0.5 * std::hypot(c.mc.standard_error[a], c.mc.standard_error[b]));
  }
  // Show the part of the plane where the reference lobe is: where MC exceeds 0.2% of its peak.
  double peak = 0.0;
  for (double y : mc.y) peak = std::max(peak, y);
  double lo = 90.0, hi = -90.0;
  for (size_t k = 0; k < mc.y.size(); ++k) {
    if (mc.y[k] < 2e-3 * peak) continue;
    lo = std::min(lo, mc.x[k]);
    hi = std::max(hi, mc.x[k]);
  }
  plot.x_min = std::max(-90.0, std::floor((lo - 5.0) / 5.0) * 5.0);
  plot.x_max = std::min(90.0, std::ceil((hi + 5.0) / 5.0) * 5.0);
  plot.series.push_back(std::move(mc));
  plot.FitYRangeFromZero();
  plot.WritePng(path);
}

std::string Fixed(double value, int decimals = 3) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.*f", decimals, value);
  return buffer;
}

void WriteHtml(const std::vector<simulate::ValidationCase>& cases, const ValidationSettings& settings, const fs::path& path) {
  std::ostringstream html;
  html << "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>svbtdf validate-model</title>\n"
       << "<style>body{font-family:sans-serif;max-width:1400px;margin:auto}"
       << "table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}"
       << ".swatch{display:inline-block;width:24px;height:4px;vertical-align:middle;margin-right:6px}"
       << "figure{display:inline-block;margin:6px}"
       << ".plot{display:inline-grid;grid-template-columns:22px auto}.plot .y{writing-mode:vertical-rl;"
       << "transform:rotate(180deg);text-align:center;font-size:13px}.plot .x,.plot figcaption{grid-column:2;"
       << "text-align:center;font-size:13px}</style></head><body>\n"
       << "<h1>Dual-microfacet model vs Monte Carlo slab</h1>\n<p>NDF " << settings.ndf << ", roughness "
       << settings.roughness << ", eta " << settings.eta << ", " << settings.samples << " paths per case, seed "
       << settings.seed << ", hemicube resolution " << settings.resolution
       << ". Errors: relative L2 against Monte Carlo over the light hemicube, cells weighted by solid "
       << "angle (docs/validation.md).</p>\n<table><tr><th>config</th><th>incidence</th><th>best alpha</th>";
  for (const ModelColumn& column : kColumns) html << "<th>" << column.label << "</th>";
  html << "<th>MC noise</th></tr>\n";
  for (const simulate::ValidationCase& c : cases) {
    html << "<tr><td>" << ToString(c.rough_sides) << "</td><td>" << c.incidence_deg << "&deg;</td><td>"
         << Fixed(c.best_alpha) << "</td>";
    for (const ModelColumn& column : kColumns) html << "<td>" << Fixed(c.errors.*column.error) << "</td>";
    html << "<td>" << Fixed(c.mc_noise, 4) << "</td></tr>\n";
  }
  html << "</table>\n<p>Cross-sections in the plane of incidence: x is the signed angle (degrees) of "
       << "the light direction from -z (straight through is at minus the incidence angle), y is rho "
       << "averaged over the two hemicube cells beside the plane.</p>\n<p>";
  for (const ModelColumn& column : kColumns) {
    html << "<span class=\"swatch\" style=\"background:" << HexColor(column.color) << "\"></span>"
         << column.label << " &nbsp; ";
  }
  html << "<span class=\"swatch\" style=\"background:#000\"></span>Monte Carlo &plusmn; 2 standard errors</p>\n";
  for (const simulate::ValidationCase& c : cases) {
    // The raster carries only digits: the axes' names are the page's.
    html << "<figure class=\"plot\"><div class=\"y\">rho, averaged beside the plane (1/sr)</div><img src=\""
         << PlotName(c) << "\" width=\"480\"><div class=\"x\">signed angle of the light from -z (degrees)</div><figcaption>"
         << ToString(c.rough_sides)
         << " rough, " << c.incidence_deg << "&deg;, best alpha " << Fixed(c.best_alpha, 2)
         << "</figcaption></figure>\n";
  }
  html << "</body></html>\n";
  common::WriteTextAtomically(path, html.str(), /*overwrite=*/false);
}

// printf into a string, for the table's fixed-width columns.
template <typename... Args>
void AppendFormatted(std::string& out, const char* format, Args... args) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, format, args...);
  out += buffer;
}

}  // namespace

std::string ValidationTable(const std::vector<simulate::ValidationCase>& cases) {
  std::string table;
  AppendFormatted(table, "%-6s %5s %6s", "config", "angle", "alpha");
  const auto width = [](const ModelColumn& column) { return std::max(8, static_cast<int>(std::strlen(column.key))); };
  for (const ModelColumn& column : kColumns) AppendFormatted(table, " %*s", width(column), column.key);
  AppendFormatted(table, " %8s %9s\n", "MC noise", "paths");
  for (const simulate::ValidationCase& c : cases) {
    AppendFormatted(table, "%-6s %5.0f %6.3f", ToString(c.rough_sides), c.incidence_deg, c.best_alpha);
    for (const ModelColumn& column : kColumns) AppendFormatted(table, " %*.4f", width(column), c.errors.*column.error);
    AppendFormatted(table, " %8.4f %9lld\n", c.mc_noise, static_cast<long long>(c.mc.paths));
  }
  return table;
}

nlohmann::json ValidationJson(const std::vector<simulate::ValidationCase>& cases, const ValidationSettings& settings) {
  nlohmann::json out;
  out["options"] = {{"ndf", settings.ndf},         {"roughness", settings.roughness},
                    {"eta", settings.eta},         {"samples", settings.samples},
                    {"seed", settings.seed},       {"resolution", settings.resolution},
                    {"max_bounces", settings.max_bounces}};
  out["cases"] = nlohmann::json::array();
  for (const simulate::ValidationCase& c : cases) out["cases"].push_back(CaseToJson(c));
  return out;
}

void WriteValidationPage(const std::vector<simulate::ValidationCase>& cases, const ValidationSettings& settings,
                         const model::Hemicube& grid, const fs::path& folder) {
  const CrossSection section = PlaneOfIncidence(grid);
  for (const simulate::ValidationCase& c : cases) WritePlot(c, section, folder / PlotName(c));
  WriteHtml(cases, settings, folder / "index.html");
}

}  // namespace svbtdf::report
