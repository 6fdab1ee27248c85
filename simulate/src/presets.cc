#include "svbtdf/simulate/presets.h"

#include "svbtdf/common/error.h"

namespace svbtdf::simulate {
namespace {

// The paper's geometry (camera 1 m from the sample centre at 45 degrees, monitor 4 cm behind an
// 8 cm sample) with stored images of `width` x `height` pixels cropped from the centre of a
// `sensor_width` x `sensor_height` sensor, focal length `f` pixels. The Zhang views are taken on
// the whole sensor with an 11 x 8 board of 25 mm squares (A3 paper) filling 60-70% of it at about
// a metre; the sample plane's board is a small one that fits the holder.
RigConfig PaperGeometry(int width, int height, double f, int sensor_width, int sensor_height) {
  RigConfig rig;
  rig.intrinsics.width = width;
  rig.intrinsics.height = height;
  rig.window = SensorWindow::Centred(width, height, sensor_width, sensor_height);
  rig.board = {11, 8, 0.025, 12, 0.85, 0.04, 1.0};
  rig.intrinsics.fx = f;
  rig.intrinsics.fy = f * 1.0005;  // a hair of pixel aspect, as real calibrations find
  rig.intrinsics.cx = (width - 1) / 2.0 + 0.013 * width;
  rig.intrinsics.cy = (height - 1) / 2.0 - 0.009 * height;
  // A long lens: mild barrel distortion and a little decentring.
  rig.intrinsics.distortion = {-0.12, 0.4, 0.0004, -0.0003, 0.0};
  rig.pose = RigConfig::PaperPose(1.0, model::kPi / 4.0);
  // The grid is shifted away from the camera by d cos(theta); the monitor is centred on the
  // straight-through point d tan(theta) behind the sample centre, so that the grid fits.
  rig.monitor.centre = model::Vec2(0.0, 0.04);
  return rig;
}

// A lab puts its monitor down in any of four ways, never quite square to the sample: the presets
// use all four, each turned and tilted by a degree or so, so that no orientation is privileged.
void LayScreen(RigConfig* rig, double orientation_deg, double tilt_deg) {
  rig->monitor.orientation_deg = orientation_deg;
  rig->monitor.tilt_deg = tilt_deg;
}

SimulationPreset Tiny() {
  SimulationPreset p;
  p.name = "tiny";
  p.description = "unit tests: 240x200 image, 32x32 texels, 6x6 dots (seconds)";
  p.rig = PaperGeometry(240, 200, 2200.0, 1280, 1024);  // a 32-degree lens
  LayScreen(&p.rig, 90.0 + 1.5, 1.0);
  p.rig.sample.texels_x = p.rig.sample.texels_y = 32;
  p.rig.dots.cols = p.rig.dots.rows = 6;
  p.rig.dots.radius_px = 4.0;
  p.rig.holder_board = {12, 12, 0.006, 0, 0.85, 0.04, 1.0};
  p.rig.sensor.bit_depth = 12;
  p.rig.dark_frames = 2;
  p.pattern = "smooth";
  p.eta = 1.5;
  // 27 slices of 2^18 paths on a 16-resolution hemicube (768 cells): about 4 s on 2 busy cores;
  // the cells holding 90% of each slice's energy have at most 5.9% relative standard error.
  p.montecarlo = {16, int64_t{1} << 18, 100};
  return p;
}

// The smallest session the fit can be judged on: 20x20 dots sample the smooth pattern's lobes
// densely enough (about 6 degrees apart) for held-out errors of a few percent.
SimulationPreset Small() {
  SimulationPreset p;
  p.name = "small";
  p.description = "fit acceptance tests: 320x256 image, 32x32 texels, 20x20 dots (about half a minute)";
  p.rig = PaperGeometry(320, 256, 2900.0, 1600, 1280);
  LayScreen(&p.rig, 180.0 - 1.0, -0.7);
  p.rig.sample.texels_x = p.rig.sample.texels_y = 32;
  p.rig.dots.cols = p.rig.dots.rows = 20;
  p.rig.dots.radius_px = 3.0;
  p.rig.holder_board = {12, 12, 0.006, 0, 0.85, 0.04, 1.0};
  p.rig.sensor.bit_depth = 12;
  p.rig.dark_frames = 2;
  p.pattern = "smooth";
  p.eta = 1.5;
  return p;
}

SimulationPreset Demo() {
  SimulationPreset p;
  p.name = "demo";
  p.description = "README demo: 480x384 image, 64x64 texels, 24x24 dots (a few minutes)";
  p.rig = PaperGeometry(480, 384, 4500.0, 2400, 1920);
  LayScreen(&p.rig, 270.0 + 0.3, 0.5);  // its window is tight around the grid: a larger turn puts a corner dot out of view
  p.rig.sample.texels_x = p.rig.sample.texels_y = 64;
  p.rig.dots.cols = p.rig.dots.rows = 24;
  p.rig.dots.radius_px = 3.0;
  p.rig.holder_board = {12, 12, 0.006, 0, 0.85, 0.04, 1.0};
  p.rig.sensor.bit_depth = 12;
  p.rig.sensor.vignetting = 0.05;
  p.pattern = "smooth";
  p.eta = 1.5;
  // 27 slices of 2^20 paths on a 24-resolution hemicube (1728 cells): about 20 s on 2 busy
  // cores; at most 4.3% relative standard error in the cells holding 90% of a slice's energy.
  p.montecarlo = {24, int64_t{1} << 20, 100};
  return p;
}

SimulationPreset PaperScale(const std::string& name) {
  SimulationPreset p;
  p.name = name;
  p.rig = PaperGeometry(1280, 1024, 12000.0, 6000, 4000);  // a 24 MP camera with a 48 mm lens
  p.rig.holder_board = {12, 12, 0.006, 0, 0.85, 0.04, 1.0};
  p.rig.sensor.bit_depth = 14;
  p.rig.sensor.vignetting = 0.08;
  p.rig.dots.radius_px = 2.0;
  p.montecarlo = {32, int64_t{1} << 23, 100};  // the paper's hemicube; minutes of tracing
  LayScreen(&p.rig, 0.5, 0.3);
  if (name == "grid-sheet") {
    p.description = "paper Table 1: grid sheet, 600x600 texels, 40x40 dots, eta 1.4, anisotropic";
    p.rig.sample.texels_x = p.rig.sample.texels_y = 600;
    p.rig.dots.cols = p.rig.dots.rows = 40;
    p.pattern = "grid-sheet";
    p.eta = 1.4;
  } else if (name == "leaf-glass") {
    p.description = "paper Table 1: leaf glass, 400x420 texels, 40x40 dots, eta 1.5";
    p.rig = PaperGeometry(1280, 1024, 11500.0, 6000, 4000);
    p.rig.holder_board = {12, 12, 0.006, 0, 0.85, 0.04, 1.0};
    p.rig.sensor.bit_depth = 14;
    p.rig.sensor.vignetting = 0.08;
    p.rig.dots.radius_px = 2.0;
    p.rig.sample.texels_x = 400;
    LayScreen(&p.rig, 90.0 - 0.4, -0.3);
    p.rig.sample.texels_y = 420;
    p.rig.dots.cols = p.rig.dots.rows = 40;
    p.pattern = "leaf-glass";
    p.eta = 1.5;
  } else {
    p.description = "paper Table 1: rice paper, 600x600 texels, 20x20 dots, eta 1.55, coloured, "
                    "8-bit sRGB-like camera with 3 brackets";
    p.rig.sample.texels_x = p.rig.sample.texels_y = 600;
    p.rig.dots.cols = p.rig.dots.rows = 20;
    p.rig.dots.radius_px = 3.0;
    p.rig.sensor.bit_depth = 8;
    LayScreen(&p.rig, 180.0 + 0.6, 0.4);
    p.rig.sensor.response = "srgb";
    p.bracket = {1.0, 8.0, 64.0};
    p.pattern = "rice-paper";
    p.eta = 1.55;
  }
  return p;
}

}  // namespace

std::vector<std::string> PresetNames() {
  return {"tiny", "small", "demo", "grid-sheet", "leaf-glass", "rice-paper"};
}

SimulationPreset MakePreset(const std::string& name) {
  if (name == "tiny") return Tiny();
  if (name == "small") return Small();
  if (name == "demo") return Demo();
  if (name == "grid-sheet" || name == "leaf-glass" || name == "rice-paper") return PaperScale(name);
  common::ThrowInvalidInput("--preset", "unknown preset '" + name + "'",
                    "use one of tiny, small, demo, grid-sheet, leaf-glass, rice-paper");
}

}  // namespace svbtdf::simulate
