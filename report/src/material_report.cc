#include "svbtdf/report/material_report.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/json.h"
#include "svbtdf/common/error.h"
#include "svbtdf/fit/material.h"
#include "svbtdf/report/compare.h"
#include "svbtdf/report/picture.h"
#include "svbtdf/simulate/truth.h"

namespace svbtdf::report {
namespace {
namespace fs = std::filesystem;

double MaxOf(const common::FloatImage& map) {
  double m = 0;
  for (float v : map.pixels) m = std::max(m, static_cast<double>(v));
  return m;
}

std::string EscapeHtml(const std::string& text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '&': out += "&amp;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

// The page being written: HTML accumulated in order, figures written at once beside it.
class Page {
 public:
  explicit Page(fs::path folder) : folder_(std::move(folder)) {}
  void Heading(const std::string& text) { html_ << "<h2>" << text << "</h2>\n"; }
  void Paragraph(const std::string& text) { html_ << "<p>" << text << "</p>\n"; }
  void Figure(const std::string& file, const Picture& picture, const std::string& caption) {
    picture.Enlarged(256).WritePng(folder_ / file);
    html_ << "<figure><img src=\"" << file << "\"><figcaption>" << caption << "</figcaption></figure>\n";
  }
  void Raw(const std::string& text) { html_ << text; }
  void Write(const std::string& title) const {
    std::ostringstream page;
    page << "<!doctype html><html><head><meta charset=\"utf-8\"><title>" << title << "</title><style>"
         << "body{font-family:sans-serif;max-width:1200px;margin:2em auto}figure{display:inline-block;margin:6px;"
         << "text-align:center}img{image-rendering:pixelated;border:1px solid #ccc}td,th{padding:2px 10px;text-align:left}"
         << "</style></head><body><h1>" << title << "</h1>\n"
         << html_.str() << "</body></html>\n";
    common::WriteTextAtomically(folder_ / "index.html", page.str(), /*overwrite=*/false);
  }

 private:
  fs::path folder_;
  std::ostringstream html_;
};

// The Monte Carlo truth's slab material of every texel, and what each one is.
void AddSlabMaterials(Page& page, const simulate::MonteCarloTruth& truth) {
  common::FloatImage index(truth.texels_x(), truth.texels_y(), 1);
  for (int y = 0; y < index.height; ++y) {
    for (int x = 0; x < index.width; ++x) index.at(x, y) = static_cast<float>(truth.material_of(truth.Index(x, y)));
  }
  const int last = static_cast<int>(truth.materials().size()) - 1;
  page.Figure("slab_material_truth.png", ScalarMap(index, 0, 0, std::max(1, last)),
              "true slab material (0 .. " + std::to_string(last) + ")");
  std::string list = "Slab materials of the Monte Carlo truth:";
  for (int m = 0; m <= last; ++m) {
    list.append(" ").append(std::to_string(m)).append(" = ").append(EscapeHtml(truth.materials()[m].label)).append(";");
  }
  list.back() = '.';
  page.Paragraph(list);
}

void AddMaps(Page& page, const fit::Material& material, const simulate::Truth* truth) {
  const simulate::MaterialTruth* parameters = truth ? truth->parameters() : nullptr;
  page.Heading("Maps");
  page.Paragraph("Colour ramp: dark purple = low, yellow = high; white = not fitted. Ranges in the captions.");
  if (truth && !parameters) {
    page.Paragraph("The Monte Carlo truth has no alpha and no NDF; its rho_d and its slab materials are shown.");
  }
  page.Figure("alpha.png", ScalarMap(material.alpha, 0, 0, 1), "alpha (0 .. 1)");
  if (parameters) {
    page.Figure("alpha_truth.png", ScalarMap(parameters->alpha, 0, 0, 1), "true alpha (0 .. 1)");
    common::FloatImage error = material.alpha;
    for (int y = 0; y < error.height; ++y) {
      for (int x = 0; x < error.width; ++x) error.at(x, y) = std::abs(material.alpha.at(x, y) - parameters->alpha.at(x, y));
    }
    page.Figure("alpha_error.png", ScalarMap(error, 0, 0, 0.1), "|alpha - true alpha| (0 .. 0.1)");
  }
  const double shadowing_max = std::max(1e-3, MaxOf(material.shadowing_roughness));
  page.Figure("shadowing.png", ScalarMap(material.shadowing_roughness, 0, 0, shadowing_max),
              "shadowing roughness (0 .. " + std::to_string(shadowing_max).substr(0, 5) + ")");
  const double k_s_max = std::max(1e-3, MaxOf(material.k_s));
  page.Figure("k_s.png", ColourMap(material.k_s, k_s_max), "k_s (RGB, white = " + std::to_string(k_s_max).substr(0, 5) + ")");
  const std::optional<common::FloatImage> true_rho_d = truth ? std::optional(truth->RhoDMap()) : std::nullopt;
  const double rho_d_max = std::max({1e-4, MaxOf(material.rho_d), true_rho_d ? MaxOf(*true_rho_d) : 0.0});
  page.Figure("rho_d.png", ColourMap(material.rho_d, rho_d_max), "rho_d (RGB, white = " + std::to_string(rho_d_max).substr(0, 6) + ")");
  if (true_rho_d) page.Figure("rho_d_truth.png", ColourMap(*true_rho_d, rho_d_max), "true rho_d (same scale)");
  if (truth && truth->montecarlo()) AddSlabMaterials(page, *truth->montecarlo());
  common::FloatImage residual = material.residual;
  for (float& r : residual.pixels) r = r < 0 ? std::nanf("") : r;
  page.Figure("residual.png", ScalarMap(residual, 0, 0, 0.2), "representatives' fit residual, relative RMSE (0 .. 0.2)");
}

void AddNdfs(Page& page, const fit::Material& material, const simulate::MaterialTruth* parameters, int max_ndfs) {
  page.Heading("NDFs of the representatives");
  page.Paragraph("ln D over the hemisphere of half-vectors seen from above (x right, y up), top 8 units of ln D." +
                 std::string(parameters ? " Each fitted NDF is followed by the true NDF of the same texel." : ""));
  const fit::MaterialEvaluator evaluator(material);
  const int count = std::min<int>(max_ndfs, static_cast<int>(material.representative_texels.size()));
  for (int r = 0; r < count; ++r) {
    // Spread the shown representatives over the list.
    const size_t index = material.representative_texels.size() * r / count;
    const int64_t texel = material.representative_texels[index];
    const int x = static_cast<int>(texel % material.width), y = static_cast<int>(texel / material.width);
    const std::string where = "texel (" + std::to_string(x) + ", " + std::to_string(y) + ")";
    page.Figure("ndf_" + std::to_string(r) + ".png", NdfPicture(evaluator.TexelNdf(x, y), 96), "fitted, " + where);
    if (parameters) {
      page.Figure("ndf_" + std::to_string(r) + "_truth.png", NdfPicture(*parameters->TexelNdf(x, y), 96), "true, " + where);
    }
  }
}

// The quality warnings (docs/quality.md), first on the page: MATERIAL/quality.json, or for a
// material written before it existed, the material's own checks computed now. Returns them.
std::vector<fit::QualityWarning> AddQuality(Page& page, const fit::Material& material, const fs::path& folder) {
  std::vector<fit::QualityWarning> warnings;
  const bool recorded = fit::ReadQuality(folder, &warnings);
  if (!recorded) warnings = fit::CheckMaterial(material, folder);
  const std::string source = recorded ? "<code>quality.json</code>"
                                      : "the material's own checks (it has no <code>quality.json</code>, so the "
                                        "calibration and processing were not checked)";
  if (warnings.empty()) {
    page.Raw("<p class=\"quality-ok\">Quality checks: no warnings (" + source + ").</p>\n");
    return warnings;
  }
  std::string html = "<div class=\"quality-warnings\" style=\"border:2px solid #c00;background:#fee;padding:4px 12px\">"
                     "<h2>Quality warnings (" + std::to_string(warnings.size()) + ")</h2><p>This material may be badly "
                     "wrong. From " + source + "; what each check means: docs/quality.md.</p><ul>\n";
  for (const fit::QualityWarning& w : warnings) {
    html += "<li><b>" + EscapeHtml(w.stage) + "</b>: " + EscapeHtml(w.what) + " (" + EscapeHtml(w.figures) +
            ")<br>likely cause: " + EscapeHtml(w.likely_cause) + "<br><small><code>" + EscapeHtml(w.file) +
            "</code></small></li>\n";
  }
  page.Raw(html + "</ul></div>\n");
  return warnings;
}

void AddCompare(Page& page, const std::string& compare_file) {
  const nlohmann::json metrics = common::ReadJsonFile(compare_file);
  if (!metrics.is_object() || !metrics.contains("texels_compared") || !metrics.contains("heldout_rel_rmse")) {
    common::ThrowFormatError(compare_file, "is not the output of 'svbtdf compare --json'",
                             "give --compare the file written by svbtdf compare MATERIAL TRUTH --json FILE");
  }
  page.Heading("Against the ground truth");
  std::string table = "<table>";
  for (const auto& [key, value] : metrics.items()) table += "<tr><th>" + key + "</th><td>" + value.dump() + "</td></tr>";
  page.Raw(table + "</table>\n");
}

}  // namespace

std::vector<fit::QualityWarning> WriteMaterialReport(const MaterialReportOptions& options) {
  if (fs::exists(options.out) && !fs::is_empty(options.out)) {
    common::ThrowInvalidInput(options.out.string(), "is not empty", "report writes into a new folder; choose another --out");
  }
  const fit::Material material = fit::ReadMaterial(options.material_folder);
  std::optional<simulate::Truth> truth;
  if (!options.truth_folder.empty()) {
    truth.emplace(simulate::ReadTruth(options.truth_folder));
    RequireSameSize(material, options.material_folder, *truth);
  }
  std::error_code error;
  fs::create_directories(options.out, error);
  if (error) common::ThrowIoError(options.out.string(), "cannot create: " + error.message());
  Page page(options.out);
  const std::vector<fit::QualityWarning> warnings = AddQuality(page, material, options.material_folder);
  page.Paragraph("Material <code>" + options.material_folder + "</code>: " + std::to_string(material.width) + " x " +
                 std::to_string(material.height) + " texels, eta " + std::to_string(material.eta).substr(0, 5) + ", " +
                 std::to_string(material.representative_texels.size()) + " representatives, NDF hemicube " +
                 std::to_string(material.ndf_resolution) + ".");
  if (!options.compare_file.empty()) AddCompare(page, options.compare_file);
  const simulate::Truth* shown_truth = truth ? &*truth : nullptr;
  AddMaps(page, material, shown_truth);
  AddNdfs(page, material, shown_truth ? shown_truth->parameters() : nullptr, options.max_ndfs);
  page.Raw("<h2>Provenance</h2><pre>" + material.provenance.dump(2) + "</pre>\n");
  page.Write("svbtdf material report");
  return warnings;
}

}  // namespace svbtdf::report
