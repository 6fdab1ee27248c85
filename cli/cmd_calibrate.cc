// svbtdf calibrate: Zhang calibration of the rig camera from a capture session, or of any camera
// from a folder of board photos (--images).

#include <glob.h>

#include <spdlog/spdlog.h>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "quality_output.h"
#include "svbtdf/calib/board_photos.h"
#include "svbtdf/calib/calibrate_session.h"
#include "svbtdf/calib/camera_calibration.h"
#include "svbtdf/process/pipeline.h"
#include "svbtdf/common/error.h"

namespace svbtdf::cli {
namespace {

struct CalibrateOptions {
  std::string session;
  std::string images_glob;
  std::string board = "chessboard:9x6:25";
  std::string json_path;
  bool fix_k3 = false;
  bool full_lens_model = false;
  bool centred_lens_model = false;
  bool strict = false;
};

std::vector<std::string> ExpandGlob(const std::string& pattern) {
  glob_t matches{};
  const int rc = ::glob(pattern.c_str(), GLOB_TILDE | GLOB_BRACE, nullptr, &matches);
  std::vector<std::string> files;
  if (rc == 0) {
    for (size_t k = 0; k < matches.gl_pathc; ++k) files.emplace_back(matches.gl_pathv[k]);
  }
  ::globfree(&matches);
  if (files.empty()) {
    common::ThrowInvalidInput("--images", "no file matches '" + pattern + "'",
                      "quote the pattern so the shell does not expand it, e.g. --images 'boards/*.png'");
  }
  return files;
}

void PrintSummary(const calib::CalibrationReport& report) {
  const calib::CameraModel& c = report.camera;
  std::printf("camera %dx%d: fx %.2f (+-%.2f)  fy %.2f (+-%.2f)  cx %.2f (+-%.2f)  cy %.2f (+-%.2f)\n", c.width,
              c.height, c.fx, report.intrinsics_std[0], c.fy, report.intrinsics_std[1], c.cx,
              report.intrinsics_std[2], c.cy, report.intrinsics_std[3]);
  std::printf("distortion k1 %.5f k2 %.5f p1 %.6f p2 %.6f k3 %.5f\n", c.distortion[0], c.distortion[1],
              c.distortion[2], c.distortion[3], c.distortion[4]);
  std::printf("reprojection RMS %.3f px over %d of %zu views (%s lens model)\n", report.rms_px, report.used_views(),
              report.views.size(), report.FittedLensModel().c_str());
  const calib::ProjectionUncertainty& u = report.projection_uncertainty;
  std::printf("projection uncertainty (1 sigma, worst direction): centre %.3f px, corners %.3f %.3f %.3f %.3f px, "
              "worst %.3f px\n",
              u.centre_px, u.corners_px[0], u.corners_px[1], u.corners_px[2], u.corners_px[3], u.worst_px);
  if (!report.narrow_lens_because.empty()) {
    spdlog::warn("narrow-lens model (square pixels, centred principal point, k1 only): {}; "
                 "--full-lens-model keeps the full one", report.narrow_lens_because);
  }
  for (const calib::ViewReport& view : report.views) {
    if (!view.used) std::printf("  dropped %s: %s\n", view.source.c_str(), view.dropped_because.c_str());
  }
}

calib::CalibrationOptions CameraOptions(const CalibrateOptions& options) {
  calib::CalibrationOptions camera;
  camera.fix_k3 = options.fix_k3;
  if (options.full_lens_model) camera.max_principal_point_std_fraction = 0;
  if (options.centred_lens_model) camera.lens_model = calib::CalibrationOptions::LensModel::kCentred;
  return camera;
}

void RunCalibrateImages(const CalibrateOptions& options) {
  const calib::BoardSpec board = calib::BoardSpec::Parse(options.board);
  const calib::CalibrationOptions calibration_options = CameraOptions(options);
  const calib::CalibrationReport report =
      calib::CalibrateFromPhotos(ExpandGlob(options.images_glob), board, calibration_options);
  PrintSummary(report);
  if (!options.json_path.empty()) {
    calib::WriteCameraCalibration(options.json_path, board, report);
    std::printf("wrote %s\n", options.json_path.c_str());
  }
}

void RunCalibrateSession(const CalibrateOptions& options) {
  calib::CalibrateSessionOptions calibrate_options;
  calibrate_options.camera = CameraOptions(options);
  const process::CalibrationStage stage = process::CalibrateAndCheck(options.session, calibrate_options);
  const calib::SessionCalibration& c = stage.calibration;
  PrintSummary(c.camera);
  const model::Vec3 centre = c.sample_plane.CameraCentre();
  const double angle = std::acos(centre.normalized().z()) * 180.0 / 3.14159265358979;
  std::printf("sample plane: reprojection RMS %.3f px; camera %.1f mm from the sample centre, %.1f degrees from its normal\n",
              c.sample_plane.rms_px, 1000.0 * centre.norm(), angle);
  int found = 0;
  for (const calib::DotPosition& dot : c.monitor.dots) found += dot.residual_mm >= 0;
  std::printf("monitor: %.2f mm behind the sample; %d of %zu dots found, residual RMS %.3f mm, max %.3f mm\n",
              1000.0 * c.monitor.distance_m, found, c.monitor.dots.size(), c.monitor.residual_rms_mm,
              c.monitor.residual_max_mm);
  std::printf("radiometry: %s response, %d bits, black offset %.1f DN\n", c.radiometry.response.c_str(),
              c.radiometry.bit_depth, c.radiometry.black_offset_dn);
  std::printf("wrote %s\n", stage.file.c_str());
  PrintQualityWarnings(stage.warnings);
  ExitIfStrict(stage.warnings, options.strict);
}

}  // namespace

void AddCalibrateCommand(CLI::App& app) {
  auto options = std::make_shared<CalibrateOptions>();
  CLI::App* calibrate = app.add_subcommand(
      "calibrate", "Calibrate a capture session (camera, sample plane, dots, radiometry), or a camera from board photos");
  CLI::Option* session = calibrate->add_option(
      "session", options->session, "capture session folder: writes SESSION/calibration.json");
  CLI::Option* images = calibrate->add_option("--images", options->images_glob, "glob of board photos, e.g. 'boards/*.png'");
  session->excludes(images);
  images->excludes(session);
  calibrate->add_option("--board", options->board, "chessboard:COLSxROWS:SQUARE_MM, charuco:COLSxROWS:SQUARE_MM:MARKER_MM[:DICT], "
                      "circles:COLSxROWS:SPACING_MM or acircles:COLSxROWS:SPACING_MM (OpenCV's circle grids)")
      ->capture_default_str();
  calibrate->add_option("--json", options->json_path, "write the calibration to this JSON file");
  calibrate->add_flag("--fix-k3", options->fix_k3, "hold the k3 distortion coefficient at zero");
  calibrate->add_flag("--full-lens-model", options->full_lens_model,
                      "estimate the principal point and all distortion terms even when the views cannot "
                      "determine them (by default a long lens falls back to the narrow-lens model)");
  calibrate->add_flag("--centred-lens-model", options->centred_lens_model,
                      "square pixels, the principal point held at the image centre, no tangential terms, k1 k2 k3 "
                      "(OpenCV's FIX_ASPECT_RATIO | FIX_PRINCIPAL_POINT | ZERO_TANGENT_DIST)")
      ->excludes("--full-lens-model");
  AddStrictFlag(calibrate, &options->strict);
  calibrate->callback([options] {
    if (!options->session.empty()) return RunCalibrateSession(*options);
    if (options->images_glob.empty()) {
      common::ThrowInvalidInput("calibrate", "needs a SESSION folder or --images 'GLOB'", "see 'svbtdf calibrate --help'");
    }
    RunCalibrateImages(*options);
  });
}

}  // namespace svbtdf::cli
