// svbtdf devices: what cameras and displays the capture rig can see, from every backend.
// A backend that cannot start (no libcamera IPA, no display server) is reported, not fatal:
// the user needs to see the rest of the list to pick a device.

#include <nlohmann/json.hpp>

#include <cstdio>
#include <functional>
#include <string>
#include <vector>

#include "commands.h"
#include "svbtdf/acquire/gphoto2_camera.h"
#include "svbtdf/acquire/libcamera_camera.h"
#include "svbtdf/acquire/sdl_display.h"
#include "svbtdf/acquire/v4l2_camera.h"
#include "svbtdf/common/error.h"

namespace svbtdf::cli {
namespace {

struct BackendReport {
  std::string name;
  std::string error;  // empty when the backend listed successfully
  std::vector<acquire::CameraInfo> cameras;
  std::vector<acquire::DisplayInfo> displays;
};

template <typename List>
void Probe(BackendReport* report, List list) {
  try {
    list(report);
  } catch (const std::exception& error) {  // svbtdf::Error or a backend's own exception
    report->error = error.what();
  }
}

std::vector<BackendReport> ProbeAll() {
  std::vector<BackendReport> reports(4);
  reports[0].name = "v4l2";
  Probe(&reports[0], [](BackendReport* r) { r->cameras = acquire::ListV4l2Cameras(); });
  reports[1].name = "libcamera";
  Probe(&reports[1], [](BackendReport* r) { r->cameras = acquire::ListLibcameraCameras(); });
  reports[2].name = "gphoto2";
  Probe(&reports[2], [](BackendReport* r) { r->cameras = acquire::ListGphoto2Cameras(); });
  reports[3].name = "sdl";
  Probe(&reports[3], [](BackendReport* r) { r->displays = acquire::ListSdlDisplays(); });
  return reports;
}

void PrintText(const std::vector<BackendReport>& reports) {
  for (const BackendReport& report : reports) {
    const bool is_display = report.name == "sdl";
    std::printf("%s (%s)\n", report.name.c_str(), is_display ? "displays" : "cameras");
    if (!report.error.empty()) {
      std::printf("  unavailable: %s\n", report.error.c_str());
      continue;
    }
    if (report.cameras.empty() && report.displays.empty()) std::printf("  none found\n");
    for (const auto& camera : report.cameras) {
      std::printf("  %s  %s\n", camera.id.c_str(), camera.model.c_str());
      if (camera.max_exposure_s > 0.0) {
        std::printf("    exposure: %g .. %g s\n", camera.min_exposure_s, camera.max_exposure_s);
      }
      for (const auto& format : camera.formats) std::printf("    format: %s\n", format.c_str());
      for (const auto& control : camera.controls) std::printf("    control: %s\n", control.c_str());
    }
    for (const auto& display : report.displays) {
      std::printf("  %s  %dx%d px\n", display.id.c_str(), display.width_px, display.height_px);
    }
  }
}

void PrintJson(const std::vector<BackendReport>& reports) {
  nlohmann::json root = {{"cameras", nlohmann::json::array()},
                         {"displays", nlohmann::json::array()},
                         {"backends", nlohmann::json::object()}};
  for (const BackendReport& report : reports) {
    root["backends"][report.name] = report.error.empty() ? "ok" : report.error;
    for (const auto& camera : report.cameras) {
      root["cameras"].push_back({{"id", camera.id},
                                 {"model", camera.model},
                                 {"formats", camera.formats},
                                 {"controls", camera.controls},
                                 {"min_exposure_s", camera.min_exposure_s},
                                 {"max_exposure_s", camera.max_exposure_s}});
    }
    for (const auto& display : report.displays) {
      root["displays"].push_back({{"id", display.id},
                                  {"width_px", display.width_px},
                                  {"height_px", display.height_px}});
    }
  }
  std::printf("%s\n", root.dump(2).c_str());
}

}  // namespace

void AddDevicesCommand(CLI::App& app) {
  auto* command = app.add_subcommand(
      "devices", "list the cameras (with formats and controls) and displays svbtdf can use");
  auto json = std::make_shared<bool>(false);
  command->add_flag("--json", *json, "machine-readable output");
  command->callback([json] {
    const auto reports = ProbeAll();
    if (*json) {
      PrintJson(reports);
    } else {
      PrintText(reports);
    }
  });
}

}  // namespace svbtdf::cli
