#include "svbtdf/report/page_data.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/image_io.h"
#include "svbtdf/common/json.h"

namespace svbtdf::report {
namespace fs = std::filesystem;
namespace {

std::string Significant(double value, int digits) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*g", digits, value);
  return text;
}

// compare's figures in words, with the targets docs/validation.md judges a fit against.
struct MetricMeaning {
  const char* name;
  bool fraction;      // shown as a percentage
  double target;      // NaN: none
  bool at_least;      // the value must be >= target (else <=)
  const char* target_text;
};

const std::map<std::string, MetricMeaning>& MetricMeanings() {
  static const std::map<std::string, MetricMeaning> meanings = {
      {"heldout_rel_rmse", {"BTDF error at the held-out dots (relative RMSE)", true, 0.05, false, "below 5%"}},
      {"all_dots_rel_rmse", {"BTDF error at every dot (relative RMSE)", true, NAN, false, ""}},
      {"alpha_within_0_05", {"texels whose alpha is within 0.05 of the truth", true, 0.90, true, "at least 90%"}},
      {"alpha_error_median", {"median error of alpha", false, NAN, false, ""}},
      {"ndf_rel_l2_median", {"median NDF error against the truth (relative L2)", true, 0.10, false, "below 10%"}},
      {"rho_d_rel_error_median", {"median error of rho_d (relative)", true, 0.02, false, "below 2%"}},
      {"texels_compared", {"texels compared", false, NAN, false, ""}},
      {"heldout_dots", {"dots held out of the fit", false, NAN, false, ""}},
  };
  return meanings;
}

// Bytes of a capture image stretched so that its brightest value is white, gamma 2.2, and
// shrunk by an integer factor to at most `max_width` (the thumbnails of the capture section).
void WriteThumbnail(const common::CameraImage& image, const fs::path& png, int max_width) {
  const int step = std::max(1, (image.width + max_width - 1) / max_width);
  const int w = image.width / step, h = image.height / step;
  double peak = 1;
  for (uint16_t v : image.pixels) peak = std::max<double>(peak, v);
  std::vector<uint8_t> rgb(static_cast<size_t>(w) * h * 3);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      for (int c = 0; c < 3; ++c) {
        const double v = image.at(x * step, y * step, image.channels == 3 ? c : 0) / peak;
        rgb[(static_cast<size_t>(y) * w + x) * 3 + c] = static_cast<uint8_t>(std::lround(255 * std::pow(v, 1 / 2.2)));
      }
    }
  }
  common::WriteRgb8Png(png, rgb, w, h, /*overwrite=*/false);
}

double SaturatedFraction(const common::CameraImage& image, double saturation_dn) {
  size_t saturated = 0;
  for (uint16_t v : image.pixels) saturated += v >= saturation_dn;
  return image.pixels.empty() ? 0.0 : static_cast<double>(saturated) / image.pixels.size();
}

// "eB", the folder of exposure bracket B in a session's dot images (docs/session-format.md).
std::string BracketName(size_t bracket) {
  std::string name(1, 'e');
  name.append(std::to_string(bracket));
  return name;
}

std::string MimeType(const fs::path& file) {
  const std::string ext = file.extension().string();
  if (ext == ".png") return "image/png";
  if (ext == ".jpg" || ext == ".jpeg") return "image/jpeg";
  return "application/octet-stream";
}

}  // namespace

std::string Base64(const std::string& bytes) {
  static const char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (size_t i = 0; i < bytes.size(); i += 3) {
    const size_t n = std::min<size_t>(3, bytes.size() - i);
    uint32_t word = 0;
    for (size_t k = 0; k < 3; ++k) word = (word << 8) | (k < n ? static_cast<uint8_t>(bytes[i + k]) : 0);
    for (size_t k = 0; k < 4; ++k) out += k <= n ? kAlphabet[(word >> (18 - 6 * k)) & 63] : '=';
  }
  return out;
}

std::string FormatPercent(double fraction) {
  if (!std::isfinite(fraction)) return "n/a";
  return Significant(100 * fraction, 3) + "%";
}

std::string FormatNumber(double value, const std::string& unit) {
  if (!std::isfinite(value)) return "n/a";
  // Counts and large values in full (1000, not 1e+03); the rest to 3 significant digits.
  const bool whole = std::abs(value) >= 1000 || (value == std::round(value) && std::abs(value) < 1e15);
  return (whole ? Significant(std::round(value), 15) : Significant(value, 3)) + (unit.empty() ? "" : " " + unit);
}

std::vector<ReadableMetric> ReadableMetrics(const nlohmann::json& compare) {
  std::vector<ReadableMetric> metrics;
  for (const auto& [key, value] : compare.items()) {
    if (!value.is_number()) continue;
    ReadableMetric m;
    m.key = key;
    m.value = value.get<double>();
    const auto known = MetricMeanings().find(key);
    if (known == MetricMeanings().end()) {
      m.name = key;
      m.text = FormatNumber(m.value);
    } else {
      const MetricMeaning& meaning = known->second;
      m.name = meaning.name;
      m.text = meaning.fraction ? FormatPercent(m.value) : FormatNumber(m.value);
      if (!std::isnan(meaning.target)) {
        m.target = meaning.target_text;
        m.met = meaning.at_least ? m.value >= meaning.target : m.value <= meaning.target;
      }
    }
    metrics.push_back(m);
  }
  return metrics;
}

nlohmann::json ToJson(const std::vector<ReadableMetric>& metrics) {
  nlohmann::json list = nlohmann::json::array();
  for (const ReadableMetric& m : metrics) {
    list.push_back({{"key", m.key}, {"name", m.name}, {"value", m.value}, {"text", m.text}, {"target", m.target},
                    {"met", m.met}});
  }
  return list;
}

nlohmann::json CalibrationSummary(const fs::path& session, std::vector<std::string>* warnings) {
  const fs::path file = session / "calibration.json";
  const nlohmann::json c = common::ReadJsonFile(file);
  if (!c.is_object() || !c.contains("camera") || !c.contains("monitor") || !c.contains("sample_plane")) {
    common::ThrowFormatError(file.string(), "is not a calibration (no camera, monitor or sample_plane)",
                             "run svbtdf calibrate on the session");
  }
  const nlohmann::json& camera = c["camera"];
  nlohmann::json views = nlohmann::json::array();
  int dropped = 0;
  for (const auto& v : camera.value("views", nlohmann::json::array())) {
    const bool used = v.value("used", true);
    dropped += !used;
    views.push_back({{"source", v.value("source", "")}, {"used", used}, {"rms_px", v.value("rms_px", -1.0)},
                     {"dropped_because", v.value("dropped_because", "")}});
  }
  if (dropped > 0) warnings->push_back(std::to_string(dropped) + " of " + std::to_string(views.size()) + " board views were dropped by the calibration");
  nlohmann::json dots = nlohmann::json::array();
  int lost = 0;
  for (const auto& d : c["monitor"].value("dots", nlohmann::json::array())) {
    const double residual = d.value("residual_mm", -1.0);
    lost += residual < 0;
    dots.push_back({{"monitor_px", d.value("monitor_px", nlohmann::json::array())}, {"residual_mm", residual}});
  }
  if (lost > 0) warnings->push_back(std::to_string(lost) + " of " + std::to_string(dots.size()) + " dots were not found in all_dots/e0");
  const std::string lens = camera.value("lens_model", "full");
  std::string why = camera.value("lens_model_because", "");
  if (why.empty()) why = lens == "full" ? "the board views determine the full model (fx, fy, cx, cy, k1, k2, p1, p2, k3)" : "";
  if (lens == "narrow") warnings->push_back("the narrow-lens model was used: " + why);
  return {{"file", file.string()},
          {"camera", {{"fx", camera.value("fx", 0.0)}, {"fy", camera.value("fy", 0.0)}, {"cx", camera.value("cx", 0.0)},
                      {"cy", camera.value("cy", 0.0)}, {"width", camera.value("width", 0)}, {"height", camera.value("height", 0)},
                      {"distortion", camera.value("distortion", nlohmann::json::array())}, {"rms_px", camera.value("rms_px", -1.0)},
                      {"lens_model", lens}, {"lens_model_because", why}}},
          {"views", views},
          {"sample_plane", {{"rms_px", c["sample_plane"].value("rms_px", -1.0)},
                            {"camera_centre_m", c["sample_plane"].value("camera_centre_m", nlohmann::json::array())}}},
          {"monitor", {{"residual_rms_mm", c["monitor"].value("residual_rms_mm", -1.0)},
                       {"residual_max_mm", c["monitor"].value("residual_max_mm", -1.0)},
                       {"orientation_deg", c["monitor"].value("orientation_deg", 0.0)},
                       {"identification", c["monitor"].value("identification", nlohmann::json::object())},
                       {"dots", dots}}},
          {"saturation_dn", c.value("radiometry", nlohmann::json::object()).value("saturation_dn", 65535.0)}};
}

nlohmann::json CaptureSummary(const fs::path& session, const fs::path& out, double saturation_dn,
                              std::vector<std::string>* warnings, int max_dot_images) {
  const nlohmann::json manifest = common::ReadJsonFile(session / "session.json");
  const nlohmann::json plan = manifest.value("rig", nlohmann::json::object()).value("acquisition_plan", nlohmann::json::object());
  const nlohmann::json exposures = plan.value("exposures_s", nlohmann::json::array());
  const fs::path images = session / "images";
  nlohmann::json thumbnails = nlohmann::json::array();
  const auto thumbnail = [&](const std::string& key, const std::string& caption) {
    const fs::path source = images / (key + ".png");
    if (!fs::is_regular_file(source)) return;
    std::string name = "capture_" + key + ".png";
    std::replace(name.begin(), name.end(), '/', '_');
    const common::CameraImage image = common::ReadCameraImage(source);
    WriteThumbnail(image, out / name, 320);
    thumbnails.push_back({{"file", name}, {"key", key}, {"caption", caption},
                          {"saturated_fraction", SaturatedFraction(image, saturation_dn)}});
  };
  thumbnail("board/v00", "a calibration board view");
  thumbnail("sample_plane/v00", "the board in the sample holder");
  thumbnail("all_dots/e0", "all dots at once");
  thumbnail("fiducials/e0", "the fiducial dots");
  // A few dots through the sample, in every bracket: the first, the middle and the last dot.
  std::vector<fs::path> dot_folders;
  if (fs::is_directory(images / "dot")) {
    for (const auto& entry : fs::directory_iterator(images / "dot")) dot_folders.push_back(entry.path());
  }
  std::sort(dot_folders.begin(), dot_folders.end());
  nlohmann::json brackets = nlohmann::json::array();
  for (size_t e = 0; e < exposures.size(); ++e) {
    double saturated = 0;
    int counted = 0;
    const size_t stride = std::max<size_t>(1, dot_folders.size() / std::max(1, max_dot_images));
    for (size_t q = 0; q < dot_folders.size(); q += stride) {
      const fs::path file = dot_folders[q] / BracketName(e) / "r0.png";
      if (!fs::is_regular_file(file)) continue;
      saturated += SaturatedFraction(common::ReadCameraImage(file), saturation_dn);
      ++counted;
    }
    const double mean = counted ? saturated / counted : 0.0;
    brackets.push_back({{"exposure_s", exposures[e]}, {"images_checked", counted}, {"saturated_fraction", mean}});
  }
  if (!dot_folders.empty()) {
    for (const size_t q : {size_t{0}, dot_folders.size() / 2, dot_folders.size() - 1}) {
      const std::string dot = dot_folders[q].filename().string();
      for (size_t e = 0; e < exposures.size(); ++e) {
        thumbnail("dot/" + dot + "/" + BracketName(e) + "/r0", "dot " + dot + ", bracket " + std::to_string(e));
      }
    }
  }
  // Longer brackets saturate by design (the HDR merge takes the shorter ones there); pixels
  // saturated in the shortest bracket have no valid measurement at all.
  if (!brackets.empty() && brackets.front()["saturated_fraction"].get<double>() > 0.001) {
    warnings->push_back("the shortest bracket saturates " + FormatPercent(brackets.front()["saturated_fraction"].get<double>()) +
                        " of the dot images' pixels: those samples are lost (shorten the exposures)");
  }
  return {{"session", session.string()}, {"preset", plan.value("name", "")}, {"dots", plan.value("dots", nlohmann::json::object()).value("positions_px", nlohmann::json::array()).size()},
          {"brackets", brackets}, {"thumbnails", thumbnails}};
}

nlohmann::json RenderSummaries(const fs::path& folder, const fs::path& out) {
  nlohmann::json renders = nlohmann::json::array();
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(folder)) {
    if (entry.path().extension() == ".json") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  for (const fs::path& file : files) {
    const nlohmann::json r = common::ReadJsonFile(file);
    if (!r.is_object() || r.value("format", "") != "svbtdf-render") continue;  // not a render's summary
    nlohmann::json shown = r;
    const std::string png = r.value("png", "");
    if (!png.empty() && fs::is_regular_file(png)) {
      const std::string name = "render_" + fs::path(png).filename().string();
      fs::copy_file(png, out / name);
      shown["shown_png"] = name;
      // Embedded as well: the page compares its live view's pixels with it, and a canvas that
      // draws a file:// image may not be read back.
      shown["png_data"] = "data:image/png;base64," + Base64(common::ReadTextFile(png));
    }
    shown["json"] = file.filename().string();
    renders.push_back(shown);
  }
  return renders;
}

std::string EmbeddedGltf(const fs::path& gltf_file) {
  nlohmann::json gltf = common::ReadJsonFile(gltf_file);
  const fs::path folder = gltf_file.parent_path();
  const auto embed = [&](nlohmann::json& entry) {
    if (!entry.is_object() || !entry.contains("uri") || !entry["uri"].is_string()) {
      common::ThrowFormatError(gltf_file.string(), "names a buffer or image without a uri", "re-run svbtdf export");
    }
    const std::string uri = entry["uri"].get<std::string>();
    if (uri.rfind("data:", 0) == 0) return;
    const fs::path file = folder / uri;
    entry["uri"] = "data:" + MimeType(file) + ";base64," + Base64(common::ReadTextFile(file));
  };
  if (gltf.contains("buffers")) for (auto& buffer : gltf["buffers"]) embed(buffer);
  if (gltf.contains("images")) for (auto& image : gltf["images"]) embed(image);
  return gltf.dump();
}

}  // namespace svbtdf::report
