#pragma once
// What the interactive report page shows besides the material's maps, gathered from the files
// the other stages wrote (docs/report.md, "The page's data"): compare's metrics in words with
// their targets, the session's calibration and capture, the renders of `svbtdf render --json`
// and the glTF export with its files embedded. Report reads these files by their documented
// formats; it does not include calib/, render/ or export/ (docs/architecture.md).

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace svbtdf::report {

// Standard base64 (RFC 4648, with padding): data the page must read from file:// arrives inside
// classic scripts, since Chrome blocks fetch() and cross-file module imports there.
std::string Base64(const std::string& bytes);

// A number as people read it: "0.83%" for a fraction, "1.42 px" for a length; 3 significant digits.
std::string FormatPercent(double fraction);
std::string FormatNumber(double value, const std::string& unit = "");

// One figure of `svbtdf compare --json` as the page shows it.
struct ReadableMetric {
  std::string key;     // compare's key
  std::string name;    // in words
  double value = 0;
  std::string text;    // formatted
  std::string target;  // what it is judged against, in words ("" when none)
  int met = -1;        // 1 met, 0 missed, -1 no target
};
// Every numeric figure of compare's JSON (unknown keys too, named by their key), those with a
// documented target (docs/validation.md) judged against it.
std::vector<ReadableMetric> ReadableMetrics(const nlohmann::json& compare);
nlohmann::json ToJson(const std::vector<ReadableMetric>& metrics);

// The calibration of SESSION (calibration.json, docs/calibration-format.md) as the page shows it:
// reprojection error per board view, the dots' residuals on the monitor plane, the lens model,
// the camera centre; `warnings` receives what is doubtful (views dropped, dots not found).
// Throws svbtdf::Error naming the file when calibration.json is unreadable.
nlohmann::json CalibrationSummary(const std::filesystem::path& session, std::vector<std::string>* warnings);

// The capture: exposure brackets from session.json, tone-mapped thumbnails of the board, the
// sample plane, all dots and a few dot images written into `out` (file names in the result), and
// the fraction of saturated pixels per bracket over up to `max_dot_images` dot images each.
nlohmann::json CaptureSummary(const std::filesystem::path& session, const std::filesystem::path& out,
                              double saturation_dn, std::vector<std::string>* warnings, int max_dot_images = 24);

// Every `svbtdf render --json` file in `folder` (format svbtdf-render): the image it wrote as
// PNG (copied into `out`), its view and scene, and its errors against its reference.
nlohmann::json RenderSummaries(const std::filesystem::path& folder, const std::filesystem::path& out);

// The .gltf with its buffer and textures turned into data: URIs (a WebGL page on file:// may not
// read local files), and export.json's figures. Throws svbtdf::Error naming the file at fault.
std::string EmbeddedGltf(const std::filesystem::path& gltf_file);

}  // namespace svbtdf::report
