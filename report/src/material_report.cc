#include "svbtdf/report/material_report.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdlib>
#include <cmath>
#include <optional>
#include <sstream>
#include <tuple>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/json.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/statistics.h"
#include "svbtdf/fit/material.h"
#include "svbtdf/fit/slice_store.h"
#include "svbtdf/report/compare.h"
#include "svbtdf/report/page_data.h"
#include "svbtdf/report/texel_inspection.h"
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

// A map's colour bar: the ramp (or, for RGB maps, black to white) from lo to hi.
struct ColourBar {
  std::string lo, hi, unit;
  bool rgb = false;
};

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
  // A map of the material: clickable (the page shows the slice of the texel under the pointer)
  // and with its colour bar, from `bar.lo` to `bar.hi` in `bar.unit`.
  void Map(const std::string& file, const Picture& picture, const std::string& caption, const ColourBar& bar,
           int texels_x, int texels_y) {
    picture.Enlarged(256).WritePng(folder_ / file);
    html_ << "<figure class=\"map\" data-texels=\"" << texels_x << " " << texels_y << "\"><img src=\"" << file
          << "\"><div class=\"bar " << (bar.rgb ? "bar-rgb" : "bar-ramp") << "\"></div><div class=\"bar-labels\"><span>"
          << bar.lo << "</span><span>" << bar.unit << "</span><span>" << bar.hi << "</span></div><figcaption>" << caption
          << "</figcaption></figure>\n";
  }
  void Raw(const std::string& text) { html_ << text; }
  // The page, its stylesheet and scripts named in `scripts` (classic scripts, in order: a file://
  // page may not import modules or fetch files).
  void Write(const std::string& title, const std::vector<std::string>& scripts = {}) const {
    std::ostringstream page;
    page << "<!doctype html><html><head><meta charset=\"utf-8\"><title>" << title << "</title>"
         << (scripts.empty() ? "" : "<link rel=\"stylesheet\" href=\"report.css\">") << "<style>"
         << "body{font-family:sans-serif;max-width:1200px;margin:2em auto}figure{display:inline-block;margin:6px;"
         << "text-align:center}img{image-rendering:pixelated;border:1px solid #ccc}td,th{padding:2px 10px;text-align:left}"
         << "</style></head><body><h1>" << title << "</h1>\n"
         << html_.str();
    for (const std::string& script : scripts) page << "<script src=\"" << script << "\"></script>\n";
    page << "</body></html>\n";
    common::WriteTextAtomically(folder_ / "index.html", page.str(), /*overwrite=*/false);
  }
  const fs::path& folder() const { return folder_; }

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

std::string Short(double value) { return FormatNumber(value); }

// |sum of channels - true sum| / true sum per texel (NaN where the truth is 0): one map of an RGB
// quantity's error.
common::FloatImage RelativeError(const common::FloatImage& fitted, const common::FloatImage& truth) {
  common::FloatImage error(fitted.width, fitted.height, 1);
  for (int y = 0; y < fitted.height; ++y) {
    for (int x = 0; x < fitted.width; ++x) {
      double f = 0, t = 0;
      for (int c = 0; c < fitted.channels; ++c) f += fitted.at(x, y, c), t += truth.at(x, y, c);
      error.at(x, y) = static_cast<float>(t > 0 ? std::abs(f - t) / t : std::nan(""));
    }
  }
  return error;
}

// A standard-error map with -1 (not known) shown as not fitted; an RGB one as its channels' mean,
// relative to the value's when `relative_to` is given.
common::FloatImage KnownOnly(const common::FloatImage& se, const common::FloatImage* relative_to = nullptr) {
  common::FloatImage out(se.width, se.height, 1);
  for (int y = 0; y < se.height; ++y) {
    for (int x = 0; x < se.width; ++x) {
      double sum = 0, value = 0;
      bool known = true;
      for (int c = 0; c < se.channels; ++c) {
        known = known && se.at(x, y, c) >= 0;
        sum += se.at(x, y, c);
        if (relative_to) value += relative_to->at(x, y, c);
      }
      double v = sum / se.channels;
      if (relative_to) v = value > 0 ? sum / value : std::nan("");
      out.at(x, y) = known ? static_cast<float>(v) : std::nanf("");
    }
  }
  return out;
}

// The 95th percentile of a map's known values (at least `floor`): a scale that one outlier does
// not flatten.
double UpperScale(const common::FloatImage& map, double floor) {
  std::vector<double> values;
  for (float v : map.pixels) {
    if (std::isfinite(v)) values.push_back(v);
  }
  return values.empty() ? floor : std::max(floor, common::Quantile(values, 0.95));
}

template <typename MapFunction>
void AddUncertaintyMaps(const fit::Material& material, const MapFunction& map) {
  const common::FloatImage alpha_se = KnownOnly(material.alpha_se);
  const double alpha_hi = UpperScale(alpha_se, 1e-3);
  map("alpha_se.png", ScalarMap(alpha_se, 0, 0, alpha_hi),
      "standard error of alpha (docs/fitting.md, \"Uncertainty\"; white: not known). On simulated sessions the truth "
      "lies within two standard errors for 86-92% of texels for alpha, 97-98% for the NDF width and for rho_d "
      "(with the flat white frame's noise), 97-99% for k_s (too wide) and 94-97% for the shadowing roughness, "
      "which one view barely constrains "
      "(docs/validation.md)", 0, alpha_hi, "unitless");
  const common::FloatImage k_s_se = KnownOnly(material.k_s_se, &material.k_s);
  const double k_s_hi = UpperScale(k_s_se, 1e-3);
  map("k_s_se.png", ScalarMap(k_s_se, 0, 0, k_s_hi), "relative standard error of k_s", 0, k_s_hi, "relative");
  const common::FloatImage rho_d_se = KnownOnly(material.rho_d_se, &material.rho_d);
  const double rho_d_hi = UpperScale(rho_d_se, 1e-3);
  map("rho_d_se.png", ScalarMap(rho_d_se, 0, 0, rho_d_hi), "relative standard error of rho_d", 0, rho_d_hi, "relative");
  const common::FloatImage shadowing_se = KnownOnly(material.shadowing_roughness_se);
  const double shadowing_hi = UpperScale(shadowing_se, 1e-3);
  map("shadowing_se.png", ScalarMap(shadowing_se, 0, 0, shadowing_hi), "standard error of the shadowing roughness", 0,
      shadowing_hi, "GGX alpha");
  const common::FloatImage width = KnownOnly(material.ndf_width);
  const double width_hi = UpperScale(width, 1e-3);
  map("ndf_width.png", ScalarMap(width, 0, 0, width_hi), "NDF width: RMS sine of the half vector's angle from the normal", 0,
      width_hi, "unitless");
  const common::FloatImage width_se = KnownOnly(material.ndf_width_se);
  const double width_se_hi = UpperScale(width_se, 1e-4);
  map("ndf_width_se.png", ScalarMap(width_se, 0, 0, width_se_hi), "standard error of the NDF width", 0, width_se_hi, "unitless");
  const common::FloatImage prediction = KnownOnly(material.prediction_se);
  const double prediction_hi = UpperScale(prediction, 1e-3);
  map("prediction_se.png", ScalarMap(prediction, 0, 0, prediction_hi),
      "predicted error of the texel's BTDF: relative RMS standard error of its prediction at its samples", 0, prediction_hi,
      "relative");
}

// A slab material's two interfaces (`svbtdf fit --model slab`): each side's roughness
// sqrt(alpha_x alpha_y) on one scale, how anisotropic it is (alpha_y / alpha_x: 1 isotropic),
// the standard errors relative to the roughness (a side the dots do not constrain shows up bright
// there) and the internal reflection's weight.
template <typename MapFunction>
void AddSlabInterfaceMaps(const fit::Material& material, const MapFunction& map) {
  const int w = material.width, h = material.height;
  common::FloatImage roughness[2] = {common::FloatImage(w, h, 1), common::FloatImage(w, h, 1)};
  common::FloatImage ratio[2] = {common::FloatImage(w, h, 1), common::FloatImage(w, h, 1)};
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const fit::SlabInterfaces slab = fit::TexelSlab(material, x, y);
      int k = 0;
      for (const fit::SlabSide* side : {&slab.entry, &slab.exit}) {
        roughness[k].at(x, y) = static_cast<float>(side->Roughness());
        ratio[k].at(x, y) = static_cast<float>(side->alpha_y / side->alpha_x);
        ++k;
      }
    }
  }
  const double roughness_max = std::max({1e-3, MaxOf(roughness[0]), MaxOf(roughness[1])});
  const char* sides[2] = {"entry, the side facing the light", "exit, the side facing the camera"};
  const char* names[2] = {"entry", "exit"};
  const common::FloatImage* se[2] = {&material.slab_entry_roughness_se, &material.slab_exit_roughness_se};
  for (int k = 0; k < 2; ++k) {
    map(std::string("slab_") + names[k] + "_roughness.png", ScalarMap(roughness[k], 0, 0, roughness_max),
        std::string("GGX roughness sqrt(alpha_x alpha_y) of the slab's ") + sides[k] +
            " (docs/fitting.md, \"The slab fit\"; both sides on one scale)",
        0, roughness_max, "GGX alpha");
    map(std::string("slab_") + names[k] + "_anisotropy.png", ScalarMap(ratio[k], 0, 0, 1),
        std::string("anisotropy of the ") + names[k] + ": alpha_y / alpha_x (1: isotropic)", 0, 1, "ratio");
    const common::FloatImage relative = KnownOnly(*se[k], &roughness[k]);
    const double hi = UpperScale(relative, 1e-3);
    map(std::string("slab_") + names[k] + "_roughness_se.png", ScalarMap(relative, 0, 0, hi),
        std::string("relative standard error of the ") + names[k] + "'s roughness (white: not known)", 0, hi, "relative");
  }
  const double halo_max = std::max(1e-3, MaxOf(material.slab_internal_reflection));
  map("slab_internal_reflection.png", ScalarMap(material.slab_internal_reflection, 0, 0, halo_max),
      "weight of the light reflected inside the slab against the light transmitted straight through (0: none)", 0,
      halo_max, "unitless");
  const double longer_max = std::max(1e-3, MaxOf(material.slab_longer_paths));
  map("slab_longer_paths.png", ScalarMap(material.slab_longer_paths, 0, 0, longer_max),
      "weight of the longer internal paths (the same shape widened by sqrt(2)) against the light transmitted straight "
      "through (0: none)",
      0, longer_max, "unitless");
}

void AddMaps(Page& page, const fit::Material& material, const simulate::Truth* truth, const std::string& lobe_error_file) {
  const simulate::MaterialTruth* parameters = truth ? truth->parameters() : nullptr;
  const int w = material.width, h = material.height;
  const auto map = [&](const std::string& file, const Picture& picture, const std::string& caption, double lo, double hi,
                       const std::string& unit, bool rgb = false) {
    page.Map(file, picture, caption, {Short(lo), Short(hi), unit, rgb}, w, h);
  };
  page.Raw("<section id=\"maps\">");
  page.Heading("3. Maps");
  page.Paragraph("Each map with its colour bar (dark purple = low, yellow = high; white = not fitted). Click a texel "
                 "on any map to see its slice and NDF in section 2.");
  if (truth && !parameters) {
    page.Paragraph("The Monte Carlo truth has no alpha and no NDF; its rho_d and its slab materials are shown.");
  }
  if (material.model == fit::MaterialModel::kSlab) AddSlabInterfaceMaps(material, map);
  if (material.model == fit::MaterialModel::kDualMicrofacet) {
    map("alpha.png", ScalarMap(material.alpha, 0, 0, 1), "alpha, the blend between rough entry (1) and rough exit (0)", 0, 1,
        "unitless");
  }
  if (parameters) {
    map("alpha_truth.png", ScalarMap(parameters->alpha, 0, 0, 1), "true alpha", 0, 1, "unitless");
    common::FloatImage error = material.alpha;
    for (int y = 0; y < error.height; ++y) {
      for (int x = 0; x < error.width; ++x) error.at(x, y) = std::abs(material.alpha.at(x, y) - parameters->alpha.at(x, y));
    }
    map("alpha_error.png", ScalarMap(error, 0, 0, 0.1), "error of alpha against the truth, |alpha - true alpha|", 0, 0.1, "unitless");
  }
  const double shadowing_max = std::max(1e-3, MaxOf(material.shadowing_roughness));
  if (material.model == fit::MaterialModel::kDualMicrofacet) map("shadowing.png", ScalarMap(material.shadowing_roughness, 0, 0, shadowing_max),
      "shadowing roughness (Smith GGX alpha; 0 = no shadowing)", 0, shadowing_max, "GGX alpha");
  const double k_s_max = std::max(1e-3, MaxOf(material.k_s));
  map("k_s.png", ColourMap(material.k_s, k_s_max), "k_s, the specular scale per colour channel", 0, k_s_max, "unitless, RGB", true);
  if (parameters) {
    map("k_s_error.png", ScalarMap(RelativeError(material.k_s, parameters->k_s), 0, 0, 0.1),
        "relative error of k_s against the truth (0.1 = 10%)", 0, 0.1, "relative");
  }
  const std::optional<common::FloatImage> true_rho_d = truth ? std::optional(truth->RhoDMap()) : std::nullopt;
  const double rho_d_max = std::max({1e-4, MaxOf(material.rho_d), true_rho_d ? MaxOf(*true_rho_d) : 0.0});
  map("rho_d.png", ColourMap(material.rho_d, rho_d_max), "rho_d, the diffuse transmission", 0, rho_d_max, "1/sr, RGB", true);
  if (true_rho_d) {
    map("rho_d_truth.png", ColourMap(*true_rho_d, rho_d_max), "true rho_d (same scale)", 0, rho_d_max, "1/sr, RGB", true);
    map("rho_d_error.png", ScalarMap(RelativeError(material.rho_d, *true_rho_d), 0, 0, 0.1),
        "relative error of rho_d against the truth (0.1 = 10%)", 0, 0.1, "relative");
  }
  if (truth && truth->montecarlo()) AddSlabMaterials(page, *truth->montecarlo());
  common::FloatImage residual = material.residual;
  for (float& r : residual.pixels) r = r < 0 ? std::nanf("") : r;
  map("residual.png", ScalarMap(residual, 0, 0, 0.2), "fit residual: relative RMSE of the texel's own samples (0.2 = 20%)", 0, 0.2, "relative");
  if (material.has_uncertainty()) AddUncertaintyMaps(material, map);
  const double clusters = std::max(1.0, MaxOf(material.cluster));
  map("cluster.png", ScalarMap(material.cluster, 0, 0, clusters), "cluster: the representative each texel belongs to", 0, clusters, "index");
  if (!lobe_error_file.empty()) {
    const common::FloatImage lobe_error = common::ReadFloatImage(lobe_error_file);
    if (lobe_error.width != w || lobe_error.height != h) {
      common::ThrowInvalidInput(lobe_error_file, "is " + std::to_string(lobe_error.width) + "x" + std::to_string(lobe_error.height) +
                                                     " texels, the material " + std::to_string(w) + "x" + std::to_string(h),
                                "give --gltf the export of this material");
    }
    map("lobe_error.png", ScalarMap(lobe_error, 0, 0, 0.5),
        "the glTF export's parametric loss: relative L2 between each texel's NDF and its GGX lobe (0.5 = 50%)", 0, 0.5, "relative");
  }
  page.Raw("</section>\n");
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

nlohmann::json ReadCompare(const std::string& compare_file) {
  const nlohmann::json metrics = common::ReadJsonFile(compare_file);
  if (!metrics.is_object() || !metrics.contains("texels_compared") || !metrics.contains("heldout_rel_rmse")) {
    common::ThrowFormatError(compare_file, "is not the output of 'svbtdf compare --json'",
                             "give --compare the file written by svbtdf compare MATERIAL TRUTH --json FILE");
  }
  return metrics;
}

void AddNumbers(Page& page, const nlohmann::json& compare, const nlohmann::json& lobes) {
  page.Raw("<section id=\"numbers\">");
  page.Heading("4. Numbers");
  std::string table = "<table class=\"metrics\"><tr><th>what</th><th>value</th><th>target</th><th>met</th></tr>";
  const auto row = [&](const std::string& name, const std::string& text, const std::string& target, int met) {
    const char* verdict = met == 1 ? "<td class=\"met\">yes</td>" : met == 0 ? "<td class=\"missed\">no</td>" : "<td></td>";
    table += "<tr><td>" + EscapeHtml(name) + "</td><td>" + text + "</td><td>" + EscapeHtml(target) + "</td>" + verdict + "</tr>";
  };
  for (const ReadableMetric& m : ReadableMetrics(compare)) row(m.name, m.text, m.target, m.met);
  if (!lobes.is_null()) {
    row("the live view's spherical Gaussians against the fitted lobes (median relative L2)",
        FormatPercent(lobes["fit_relative_l2_median"].get<double>()), "", -1);
  }
  page.Raw(table + "</table>\n");
  if (compare.is_null()) page.Paragraph("No comparison with a truth was given (<code>--compare</code>).");
  page.Raw("</section>\n");
}

// The first page section: the live views (filled by report.js) and the renders beside them.
void AddLiveSection(Page& page, const nlohmann::json& renders, bool has_gltf) {
  page.Raw("<section id=\"live\">");
  page.Heading("1. The material, live");
  if (!has_gltf) page.Paragraph("No glTF export was given (<code>--gltf</code>): the glTF view is off.");
  page.Raw(std::string("<div class=\"live\"><div class=\"viewer\"><div class=\"tabs\">") +
           (has_gltf ? "<button data-mode=\"gltf\">glTF export (three.js)</button>" : "") +
           "<button data-mode=\"sg\">full material (spherical Gaussians)</button> <label>light: <select id=\"light\">"
           "<option value=\"checker\">checkerboard behind</option><option value=\"room\">room environment</option>"
           "</select></label></div><canvas id=\"viewer\" width=\"512\" height=\"512\"></canvas>"
           "<p id=\"viewer-status\"></p><p id=\"sg-difference\"></p></div>\n<div class=\"renders\">");
  if (renders.empty()) page.Paragraph("No renders were given (<code>--renders</code>).");
  std::string table = "<table class=\"renders\"><tr><th>view (theta, phi)</th><th>what</th><th>image</th><th>error against its reference</th></tr>";
  for (const auto& r : renders) {
    const nlohmann::json& camera = r["camera"];
    const std::string view = FormatNumber(camera.value("theta_deg", 0.0)) + "&deg;, " + FormatNumber(camera.value("phi_deg", 0.0)) + "&deg;";
    std::string error = "(the reference)";
    if (r.contains("relative_rmse")) {
      error = "relative RMSE " + FormatPercent(r["relative_rmse"].get<double>()) + ", SSIM " + FormatNumber(r["ssim"].get<double>()) +
              "<br><small>against " + EscapeHtml(fs::path(r.value("reference", "")).filename().string()) + "</small>";
    }
    const std::string image = r.contains("shown_png") ? "<img src=\"" + r["shown_png"].get<std::string>() + "\">" : "(no PNG)";
    table += "<tr><td>" + view + "</td><td>" + EscapeHtml(r.value("surface", "")) + (r.value("parametric", false) ? " (GGX lobes)" : "") +
             "<br><small>" + EscapeHtml(r.value("material", "")) + ", " + std::to_string(r.value("samples_per_pixel", 0)) +
             " spp</small></td><td>" + image + "</td><td>" + error + "</td></tr>";
  }
  if (!renders.empty()) page.Raw(table + "</table>");
  page.Raw("</div></div></section>\n");
}

void AddInspector(Page& page, bool has_store) {
  page.Raw("<section id=\"inspect\">");
  page.Heading("2. Measured against fitted at a texel");
  page.Paragraph(std::string("Click a texel on any map below. Left: the texel's samples over the light directions (where each "
                             "dot's light came from, seen from above), measured and fitted on one colour scale; held-out dots "
                             "ringed. Middle: fitted against measured, one point per dot. Right: the texel's NDF, fitted and true.") +
                 (has_store ? "" : " <b>The slice store was not found: only the fitted side is shown.</b>"));
  page.Raw("<div id=\"inspector\"><p id=\"inspect-title\">No texel chosen yet.</p>"
           "<canvas id=\"slice-measured\" width=\"260\" height=\"290\"></canvas>"
           "<canvas id=\"slice-fitted\" width=\"260\" height=\"290\"></canvas>"
           "<canvas id=\"slice-scatter\" width=\"290\" height=\"290\"></canvas>"
           "<canvas id=\"ndf-fitted\" width=\"150\" height=\"170\"></canvas>"
           "<canvas id=\"ndf-truth\" width=\"150\" height=\"170\"></canvas></div></section>\n");
}

void AddCalibration(Page& page, const nlohmann::json& calibration, const nlohmann::json& capture) {
  page.Raw("<section id=\"calibration\">");
  page.Heading("5. The calibration and the capture");
  if (calibration.is_null()) {
    page.Paragraph("The capture session was not found (<code>--session</code>, or the material's provenance): no calibration shown.");
    page.Raw("</section>\n");
    return;
  }
  const nlohmann::json& camera = calibration["camera"];
  const nlohmann::json& centre = calibration["sample_plane"]["camera_centre_m"];
  std::string centre_text = "n/a";
  if (centre.size() == 3) {
    centre_text = "(" + FormatNumber(1000 * centre[0].get<double>()) + ", " + FormatNumber(1000 * centre[1].get<double>()) + ", " +
                  FormatNumber(1000 * centre[2].get<double>()) + ") mm";
  }
  std::string table = "<table class=\"metrics\">";
  const auto row = [&](const std::string& what, const std::string& value) { table += "<tr><td>" + what + "</td><td>" + value + "</td></tr>"; };
  row("lens model", EscapeHtml(camera["lens_model"].get<std::string>()) + ": " + EscapeHtml(camera["lens_model_because"].get<std::string>()));
  row("focal length", FormatNumber(camera["fx"].get<double>(), "px") + " x " + FormatNumber(camera["fy"].get<double>(), "px"));
  row("principal point", "(" + FormatNumber(camera["cx"].get<double>()) + ", " + FormatNumber(camera["cy"].get<double>()) + ") px");
  row("reprojection error over the used board views (RMS)", FormatNumber(camera["rms_px"].get<double>(), "px"));
  row("reprojection error of the board in the sample holder (RMS)", FormatNumber(calibration["sample_plane"]["rms_px"].get<double>(), "px"));
  row("camera centre in the sample frame", centre_text);
  row("dots' residuals on the monitor plane", "RMS " + FormatNumber(calibration["monitor"]["residual_rms_mm"].get<double>(), "mm") +
                                                  ", worst " + FormatNumber(calibration["monitor"]["residual_max_mm"].get<double>(), "mm") +
                                                  " (target: worst below 0.2 mm)");
  row("monitor orientation", FormatNumber(calibration["monitor"]["orientation_deg"].get<double>(), "degrees"));
  page.Raw(table + "</table>\n");
  page.Raw("<div class=\"plots\"><canvas id=\"plot-views\" width=\"420\" height=\"260\"></canvas>"
           "<canvas id=\"plot-dots\" width=\"420\" height=\"260\"></canvas></div>\n");
  if (!capture.is_null()) {
    std::string brackets = "<table class=\"metrics\"><tr><th>exposure bracket</th><th>exposure</th><th>dot images checked</th><th>saturated pixels</th></tr>";
    int e = 0;
    for (const auto& b : capture["brackets"]) {
      brackets += "<tr><td>" + std::to_string(e++) + "</td><td>" + FormatNumber(b["exposure_s"].get<double>(), "s") + "</td><td>" +
                  std::to_string(b["images_checked"].get<int>()) + "</td><td>" + FormatPercent(b["saturated_fraction"].get<double>()) + "</td></tr>";
    }
    page.Raw(brackets + "</table>\n<p class=\"thumbnails\">");
    for (const auto& t : capture["thumbnails"]) {
      page.Raw("<figure><img src=\"" + t["file"].get<std::string>() + "\"><figcaption>" + EscapeHtml(t["caption"].get<std::string>()) +
               "<br>saturated: " + FormatPercent(t["saturated_fraction"].get<double>()) + "</figcaption></figure>");
    }
    page.Raw("</p>\n");
  }
  page.Raw("</section>\n");
}

void AddDoubts(Page& page, const std::vector<std::string>& doubts) {
  if (doubts.empty()) return;
  std::string html = "<div class=\"doubts\"><h2>Doubtful in this capture (" + std::to_string(doubts.size()) + ")</h2><ul>";
  for (const std::string& d : doubts) html += "<li>" + EscapeHtml(d) + "</li>";
  page.Raw(html + "</ul></div>\n");
}

// A generated data script: `window.NAME = VALUE;` (the page reads no file itself).
void WriteDataScript(const fs::path& file, const std::string& name, const std::string& value) {
  common::WriteTextAtomically(file, "window." + name + " = " + value + ";\n", /*overwrite=*/false);
}

fs::path FromProvenance(const fit::Material& material, const std::string& given, const char* key) {
  if (!given.empty()) return given;
  return common::StringOr(material.provenance, key);
}

}  // namespace

std::vector<fs::path> ReportAssetFiles(const fs::path& assets) {
  if (!assets.empty()) return {assets / "three-bundle.js", assets / "report.js", assets / "report.css"};
  if (const char* folder = std::getenv("SVBTDF_REPORT_ASSETS")) return ReportAssetFiles(fs::path(folder));
  const fs::path source(SVBTDF_SOURCE_DIR);
  return {source / "tools" / "report" / "dist" / "three-bundle.js", source / "report" / "assets" / "report.js",
          source / "report" / "assets" / "report.css"};
}

std::vector<fit::QualityWarning> WriteMaterialReport(const MaterialReportOptions& options) {
  if (fs::exists(options.out) && !fs::is_empty(options.out)) {
    common::ThrowInvalidInput(options.out.string(), "is not empty", "report writes into a new folder; choose another --out");
  }
  const std::vector<fs::path> assets = ReportAssetFiles(options.assets);
  for (const fs::path& asset : assets) {
    if (!fs::is_regular_file(asset)) {
      common::ThrowIoError(asset.string(), "is missing: the report page needs it",
                           "run scripts/install-deps.sh (it bundles three.js into tools/report/dist), or set SVBTDF_REPORT_ASSETS");
    }
  }
  const fit::Material material = fit::ReadMaterial(options.material_folder);
  std::optional<simulate::Truth> truth;
  if (!options.truth_folder.empty()) {
    truth.emplace(simulate::ReadTruth(options.truth_folder));
    RequireSameSize(material, options.material_folder, *truth);
  }
  const nlohmann::json compare = options.compare_file.empty() ? nlohmann::json() : ReadCompare(options.compare_file);
  if (!options.renders_folder.empty() && !fs::is_directory(options.renders_folder)) {
    common::ThrowInvalidInput(options.renders_folder, "is not a folder", "give --renders the folder of svbtdf render --json summaries");
  }
  if (!options.gltf_file.empty() && !fs::is_regular_file(options.gltf_file)) {
    common::ThrowInvalidInput(options.gltf_file, "is not a file", "give --gltf the .gltf that svbtdf export wrote");
  }
  std::error_code error;
  fs::create_directories(options.out, error);
  if (error) common::ThrowIoError(options.out.string(), "cannot create: " + error.message());
  for (const fs::path& asset : assets) fs::copy_file(asset, options.out / asset.filename());
  Page page(options.out);
  const std::vector<fit::QualityWarning> warnings = AddQuality(page, material, options.material_folder);

  // What the capture says (section 5), first, so that its doubts head the page.
  std::vector<std::string> doubts;
  const fs::path session = FromProvenance(material, options.session_folder, "session");
  nlohmann::json calibration, capture;
  if (!session.empty() && fs::is_regular_file(session / "calibration.json")) {
    calibration = CalibrationSummary(session, &doubts);
    capture = CaptureSummary(session, options.out, calibration["saturation_dn"].get<double>(), &doubts);
  } else if (!options.session_folder.empty()) {
    common::ThrowInvalidInput(options.session_folder, "has no calibration.json", "give --session a calibrated capture session");
  }
  const fs::path store_folder = FromProvenance(material, options.store_folder, "processed");
  std::optional<fit::SliceStore> store;
  if (!store_folder.empty() && fs::is_regular_file(store_folder / "processed.json")) {
    store.emplace(fit::SliceStore::Open(store_folder));
    if (store->geometry().texels_x != material.width || store->geometry().texels_y != material.height) {
      common::ThrowInvalidInput(store_folder.string(), "is not the slice store of this material (another texel grid)");
    }
  } else if (!options.store_folder.empty()) {
    common::ThrowInvalidInput(options.store_folder, "is not a slice store (no processed.json)");
  }
  const int masked = [&] {
    int n = 0;
    for (float r : material.residual.pixels) n += r < 0;
    return n;
  }();
  if (masked > 0) doubts.push_back(std::to_string(masked) + " texels were not fitted (masked: too few valid samples)");
  AddDoubts(page, doubts);
  page.Paragraph("Material <code>" + options.material_folder + "</code>: " + std::to_string(material.width) + " x " +
                 std::to_string(material.height) + " texels, eta " + FormatNumber(material.eta) + ", " +
                 std::to_string(material.representative_texels.size()) + " representatives, NDF hemicube " +
                 std::to_string(material.ndf_resolution) +
                 (material.internal_reflection ? ", with the light reflected inside the slab (T R R T) in every texel's rho" : "") +
                 ".");

  // Section 1: the live views and the renders.
  const nlohmann::json renders = options.renders_folder.empty() ? nlohmann::json::array()
                                                                 : RenderSummaries(options.renders_folder, options.out);
  std::string lobe_error_file;
  if (!options.gltf_file.empty()) {
    WriteDataScript(options.out / "report-gltf.js", "SVBTDF_GLTF", nlohmann::json(EmbeddedGltf(options.gltf_file)).dump());
    const fs::path gltf(options.gltf_file);
    const fs::path lobe_error = gltf.parent_path() / (gltf.stem().string() + "_lobe_error.exr");
    if (fs::is_regular_file(lobe_error)) lobe_error_file = lobe_error.string();
  }
  AddLiveSection(page, renders, !options.gltf_file.empty());
  const nlohmann::json lobes = LobeData(material, MakeTexelGrid(material.width, material.height, options.lobe_grid), options.threads);

  // Section 2: the inspector, whose data covers a grid of texels.
  AddInspector(page, store.has_value());
  const simulate::MaterialTruth* parameters = truth ? truth->parameters() : nullptr;
  const int dots = store ? static_cast<int>(store->geometry().dots.size()) : 0;
  const int side = InspectionGridSide(material.width, material.height, dots, options.inspect_grid, options.inspect_budget);
  std::vector<int> held_out;
  const nlohmann::json& holdout = material.provenance.value("holdout", nlohmann::json::object());
  if (holdout.is_object() && holdout.contains("dots")) {
    held_out = common::IntegerArrayAt<int>(holdout, "dots", (fs::path(options.material_folder) / "material.json").string());
  }
  const nlohmann::json inspection = InspectionData(material, store ? &*store : nullptr, parameters, held_out,
                                                   MakeTexelGrid(material.width, material.height, side), options.threads);

  const simulate::Truth* shown_truth = truth ? &*truth : nullptr;
  AddMaps(page, material, shown_truth, lobe_error_file);
  AddNumbers(page, compare, lobes);
  AddCalibration(page, calibration, capture);
  AddNdfs(page, material, shown_truth ? shown_truth->parameters() : nullptr, options.max_ndfs);
  page.Raw("<section id=\"validation\">");
  page.Heading("6. The model against Monte Carlo");
  if (options.validation_page.empty()) {
    page.Paragraph("Not given (<code>--validation</code>, the page of <code>svbtdf validate-model --plots DIR</code>).");
  } else {
    const fs::path link = fs::relative(fs::absolute(options.validation_page), fs::absolute(options.out));
    page.Paragraph("The dual-microfacet model against a Monte Carlo slab, with plane-of-incidence plots: <a href=\"" +
                   EscapeHtml(link.string()) + "\">" + EscapeHtml(link.string()) + "</a> (docs/validation.md explains the cases).");
  }
  page.Raw("</section>\n");
  page.Raw("<h2>Provenance</h2><pre>" + EscapeHtml(material.provenance.dump(2)) + "</pre>\n");

  const nlohmann::json data = {{"format", "svbtdf-report-data"}, {"version", 1},
                               {"material", {{"folder", options.material_folder}, {"width", material.width}, {"height", material.height},
                                             {"width_m", material.width_m}, {"height_m", material.height_m}, {"eta", material.eta}}},
                               {"metrics", ToJson(ReadableMetrics(compare.is_null() ? nlohmann::json::object() : compare))},
                               {"renders", renders}, {"calibration", calibration}, {"capture", capture},
                               {"doubts", doubts}, {"has_gltf", !options.gltf_file.empty()}};
  WriteDataScript(options.out / "report-data.js", "SVBTDF_REPORT", data.dump());
  WriteDataScript(options.out / "report-texels.js", "SVBTDF_TEXELS", inspection.dump());
  WriteDataScript(options.out / "report-lobes.js", "SVBTDF_LOBES", lobes.dump());
  std::vector<std::string> scripts = {"three-bundle.js", "report-data.js", "report-texels.js", "report-lobes.js"};
  if (!options.gltf_file.empty()) scripts.push_back("report-gltf.js");
  scripts.push_back("report.js");
  page.Write("svbtdf material report", scripts);
  return warnings;
}

}  // namespace svbtdf::report
