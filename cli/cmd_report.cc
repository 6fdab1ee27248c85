// svbtdf report MATERIAL --out DIR [--truth DIR/truth] [--compare FILE]: pictures of a fitted
// material (its maps and NDFs), beside the ground truth when there is one, in an HTML page.

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "commands.h"
#include "line_plot.h"
#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/fit/material.h"
#include "svbtdf/fit/quality.h"
#include "svbtdf/simulate/session_writer.h"

namespace svbtdf::cli {
namespace {
namespace fs = std::filesystem;

struct ReportOptions {
  std::string material, out, truth, compare;
  int max_ndfs = 12;
};

// A perceptually ordered ramp (viridis, five stops), for scalar maps.
Rgb8 Ramp(double t) {
  static constexpr double kStops[5][3] = {
      {68, 1, 84}, {59, 82, 139}, {33, 145, 140}, {94, 201, 98}, {253, 231, 37}};
  if (!std::isfinite(t)) return {255, 255, 255};
  t = std::clamp(t, 0.0, 1.0) * 4.0;
  const int k = std::min(3, static_cast<int>(t));
  const double f = t - k;
  Rgb8 c;
  for (int i = 0; i < 3; ++i) c[i] = static_cast<unsigned char>(std::lround((1 - f) * kStops[k][i] + f * kStops[k + 1][i]));
  return c;
}

// An 8-bit picture being drawn; small maps are enlarged by pixel replication to `min_side`.
struct Picture {
  int width = 0, height = 0;
  std::vector<unsigned char> pixels;
  Picture(int w, int h) : width(w), height(h), pixels(static_cast<size_t>(w) * h * 3, 255) {}
  void Set(int x, int y, const Rgb8& c) { std::copy(c.begin(), c.end(), pixels.begin() + (static_cast<size_t>(y) * width + x) * 3); }
  Picture Enlarged(int min_side) const {
    const int scale = std::max(1, min_side / std::max(1, std::max(width, height)));
    Picture big(width * scale, height * scale);
    for (int y = 0; y < big.height; ++y) {
      for (int x = 0; x < big.width; ++x) {
        const size_t from = (static_cast<size_t>(y / scale) * width + x / scale) * 3;
        std::copy_n(pixels.begin() + from, 3, big.pixels.begin() + (static_cast<size_t>(y) * big.width + x) * 3);
      }
    }
    return big;
  }
};

// One scalar channel of a map, scaled from [lo, hi] to the ramp.
Picture ScalarMap(const FloatImage& map, int channel, double lo, double hi) {
  Picture p(map.width, map.height);
  for (int y = 0; y < map.height; ++y) {
    for (int x = 0; x < map.width; ++x) p.Set(x, y, Ramp((map.at(x, y, channel) - lo) / (hi - lo)));
  }
  return p;
}

// An RGB map scaled so that `white` maps to 255.
Picture ColourMap(const FloatImage& map, double white) {
  Picture p(map.width, map.height);
  for (int y = 0; y < map.height; ++y) {
    for (int x = 0; x < map.width; ++x) {
      Rgb8 c;
      for (int k = 0; k < 3; ++k) {
        c[k] = static_cast<unsigned char>(std::lround(255 * std::pow(std::clamp(map.at(x, y, k) / white, 0.0, 1.0), 1 / 2.2)));
      }
      p.Set(x, y, c);
    }
  }
  return p;
}

// The NDF seen from above (orthographic over the hemisphere of h), ln D over its top 8 units.
Picture NdfPicture(const Ndf& ndf, int side) {
  Picture p(side, side);
  std::vector<double> ln_d(static_cast<size_t>(side) * side, std::nan(""));
  double peak = -1e300;
  for (int y = 0; y < side; ++y) {
    for (int x = 0; x < side; ++x) {
      const double u = (x + 0.5) / side * 2 - 1, v = 1 - (y + 0.5) / side * 2;
      if (u * u + v * v >= 1) continue;
      const double d = ndf.D(Vec3(u, v, std::sqrt(1 - u * u - v * v)));
      ln_d[static_cast<size_t>(y) * side + x] = std::log(std::max(d, 1e-30));
      peak = std::max(peak, ln_d[static_cast<size_t>(y) * side + x]);
    }
  }
  for (int y = 0; y < side; ++y) {
    for (int x = 0; x < side; ++x) p.Set(x, y, Ramp((ln_d[static_cast<size_t>(y) * side + x] - peak + 8) / 8));
  }
  return p;
}

double MaxOf(const FloatImage& map) {
  double m = 0;
  for (float v : map.pixels) m = std::max(m, static_cast<double>(v));
  return m;
}

class Page {
 public:
  explicit Page(fs::path folder) : folder_(std::move(folder)) {}
  void Heading(const std::string& text) { html_ << "<h2>" << text << "</h2>\n"; }
  void Paragraph(const std::string& text) { html_ << "<p>" << text << "</p>\n"; }
  void Figure(const std::string& file, const Picture& picture, const std::string& caption) {
    const Picture big = picture.Enlarged(256);
    WriteRgb8PngAtomically(folder_ / file, big.pixels, big.width, big.height);
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
    WriteTextAtomically(folder_ / "index.html", page.str(), /*overwrite=*/false);
  }

 private:
  fs::path folder_;
  std::ostringstream html_;
};

void AddMaps(Page& page, const fit::Material& material, const std::optional<MaterialTruth>& truth) {
  page.Heading("Maps");
  page.Paragraph("Colour ramp: dark purple = low, yellow = high; white = not fitted. Ranges in the captions.");
  page.Figure("alpha.png", ScalarMap(material.alpha, 0, 0, 1), "alpha (0 .. 1)");
  if (truth) page.Figure("alpha_truth.png", ScalarMap(truth->alpha, 0, 0, 1), "true alpha (0 .. 1)");
  if (truth) {
    FloatImage error = material.alpha;
    for (int y = 0; y < error.height; ++y) {
      for (int x = 0; x < error.width; ++x) error.at(x, y) = std::abs(material.alpha.at(x, y) - truth->alpha.at(x, y));
    }
    page.Figure("alpha_error.png", ScalarMap(error, 0, 0, 0.1), "|alpha - true alpha| (0 .. 0.1)");
  }
  const double shadowing_max = std::max(1e-3, MaxOf(material.shadowing_roughness));
  page.Figure("shadowing.png", ScalarMap(material.shadowing_roughness, 0, 0, shadowing_max),
              "shadowing roughness (0 .. " + std::to_string(shadowing_max).substr(0, 5) + ")");
  const double k_s_max = std::max(1e-3, MaxOf(material.k_s));
  page.Figure("k_s.png", ColourMap(material.k_s, k_s_max), "k_s (RGB, white = " + std::to_string(k_s_max).substr(0, 5) + ")");
  const double rho_d_max = std::max({1e-4, MaxOf(material.rho_d), truth ? MaxOf(truth->rho_d) : 0.0});
  page.Figure("rho_d.png", ColourMap(material.rho_d, rho_d_max), "rho_d (RGB, white = " + std::to_string(rho_d_max).substr(0, 6) + ")");
  if (truth) page.Figure("rho_d_truth.png", ColourMap(truth->rho_d, rho_d_max), "true rho_d (same scale)");
  FloatImage residual = material.residual;
  for (float& r : residual.pixels) r = r < 0 ? std::nanf("") : r;
  page.Figure("residual.png", ScalarMap(residual, 0, 0, 0.2), "representatives' fit residual, relative RMSE (0 .. 0.2)");
}

void AddNdfs(Page& page, const fit::Material& material, const std::optional<MaterialTruth>& truth, int max_ndfs) {
  page.Heading("NDFs of the representatives");
  page.Paragraph("ln D over the hemisphere of half-vectors seen from above (x right, y up), top 8 units of ln D." +
                 std::string(truth ? " Each fitted NDF is followed by the true NDF of the same texel." : ""));
  const fit::MaterialEvaluator evaluator(material);
  const int count = std::min<int>(max_ndfs, static_cast<int>(material.representative_texels.size()));
  for (int r = 0; r < count; ++r) {
    // Spread the shown representatives over the list.
    const size_t index = material.representative_texels.size() * r / count;
    const int64_t texel = material.representative_texels[index];
    const int x = static_cast<int>(texel % material.width), y = static_cast<int>(texel / material.width);
    const std::string where = "texel (" + std::to_string(x) + ", " + std::to_string(y) + ")";
    page.Figure("ndf_" + std::to_string(r) + ".png", NdfPicture(evaluator.TexelNdf(x, y), 96), "fitted, " + where);
    if (truth) page.Figure("ndf_" + std::to_string(r) + "_truth.png", NdfPicture(*truth->TexelNdf(x, y), 96), "true, " + where);
  }
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
  const nlohmann::json metrics = nlohmann::json::parse(ReadTextFile(compare_file));
  page.Heading("Against the ground truth");
  std::string table = "<table>";
  for (const auto& [key, value] : metrics.items()) table += "<tr><th>" + key + "</th><td>" + value.dump() + "</td></tr>";
  page.Raw(table + "</table>\n");
}

void RunReport(const ReportOptions& options) {
  if (fs::exists(options.out) && !fs::is_empty(options.out)) {
    ThrowInvalidInput(options.out, "is not empty", "report writes into a new folder; choose another --out");
  }
  const fit::Material material = fit::ReadMaterial(options.material);
  std::optional<MaterialTruth> truth;
  if (!options.truth.empty()) {
    truth = ReadMaterialTruth(options.truth);
    if (truth->width() != material.width || truth->height() != material.height) {
      ThrowInvalidInput(options.truth, "is not the size of the material", "give the truth of the session the material was fitted from");
    }
  }
  std::error_code error;
  fs::create_directories(options.out, error);
  if (error) ThrowIoError(options.out, "cannot create: " + error.message());
  Page page(options.out);
  const std::vector<fit::QualityWarning> warnings = AddQuality(page, material, options.material);
  page.Paragraph("Material <code>" + options.material + "</code>: " + std::to_string(material.width) + " x " +
                 std::to_string(material.height) + " texels, eta " + std::to_string(material.eta).substr(0, 5) + ", " +
                 std::to_string(material.representative_texels.size()) + " representatives, NDF hemicube " +
                 std::to_string(material.ndf_resolution) + ".");
  if (!options.compare.empty()) AddCompare(page, options.compare);
  AddMaps(page, material, truth);
  AddNdfs(page, material, truth, options.max_ndfs);
  page.Raw("<h2>Provenance</h2><pre>" + material.provenance.dump(2) + "</pre>\n");
  page.Write("svbtdf material report");
  std::printf("report: %s\n", (fs::path(options.out) / "index.html").c_str());
  if (!warnings.empty()) {
    std::fflush(stdout);
    std::fprintf(stderr, "svbtdf: the report shows %zu quality warning%s at its top\n", warnings.size(),
                 warnings.size() == 1 ? "" : "s");
  }
}

}  // namespace

void AddReportCommand(CLI::App& app) {
  auto options = std::make_shared<ReportOptions>();
  CLI::App* report = app.add_subcommand("report", "Pictures of a fitted material (maps, NDFs) in an HTML page");
  report->add_option("material", options->material, "fitted material folder")->required();
  report->add_option("--out", options->out, "new folder for the report")->required();
  report->add_option("--truth", options->truth, "ground truth written by 'svbtdf simulate' (OUT/truth), shown alongside");
  report->add_option("--compare", options->compare, "metrics written by 'svbtdf compare --json', shown as a table");
  report->add_option("--ndfs", options->max_ndfs, "number of representatives' NDFs to show")->capture_default_str();
  report->callback([options] { RunReport(*options); });
}

}  // namespace svbtdf::cli
