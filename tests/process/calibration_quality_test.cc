// The quality checks of a calibration (docs/quality.md, "calibrate").
#include <gtest/gtest.h>

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

#include "quality_warnings.h"
#include "svbtdf/process/calibration_quality.h"

namespace svbtdf::process {
namespace {
using fit::QualityWarning;
using testing::Checks;
using testing::Find;
using testing::Has;

// A calibration as a good `svbtdf calibrate` writes it: 36 dots found within blob noise, all
// board views used at 0.1 px.
calib::SessionCalibration GoodCalibration() {
  calib::SessionCalibration c;
  c.camera.rms_px = 0.08;
  for (int v = 0; v < 8; ++v) {
    calib::ViewReport view;
    view.source = "board/v0" + std::to_string(v);
    view.used = true;
    view.rms_px = 0.08;
    c.camera.views.push_back(view);
  }
  c.sample_plane.rms_px = 0.12;
  for (int q = 0; q < 36; ++q) {
    calib::DotPosition dot;
    dot.residual_mm = 0.01 + 0.001 * q;
    c.monitor.dots.push_back(dot);
  }
  c.monitor.residual_rms_mm = 0.02;
  c.monitor.residual_max_mm = 0.045;
  return c;
}


TEST(QualityCheck, AGoodCalibrationDrawsNoWarning) {
  EXPECT_TRUE(CheckCalibration(GoodCalibration(), "calibration.json").empty());
  // The truth calibration of the tests (no views, no residuals) neither.
  EXPECT_TRUE(CheckCalibration(calib::SessionCalibration{}, "calibration.json").empty());
}

TEST(QualityCheck, DotsFarFromTheGridAreAWarningWithFiguresAndCause) {
  calib::SessionCalibration c = GoodCalibration();
  c.monitor.dots[7].residual_mm = 2.4;
  c.monitor.dots[8].residual_mm = 1.1;
  c.monitor.residual_max_mm = 2.4;
  c.monitor.residual_rms_mm = 0.45;
  const auto warnings = CheckCalibration(c, "SESSION/calibration.json");
  ASSERT_EQ(Checks(warnings), std::vector<std::string>{"dot-residual"});
  const QualityWarning& w = warnings.front();
  EXPECT_EQ(w.stage, "calibrate");
  const std::string line = w.Line();
  EXPECT_EQ(line.rfind("warning: calibrate: SESSION/calibration.json: ", 0), 0u) << line;
  EXPECT_NE(line.find("RMS 0.450 mm, max 2.400 mm at dot 7"), std::string::npos) << line;
  EXPECT_NE(line.find("2 of 36 found dots"), std::string::npos) << line;
  EXPECT_NE(line.find("mislabelled (monitor orientation"), std::string::npos) << line;
  // The RMS alone also fires (many dots a little off).
  calib::SessionCalibration rms = GoodCalibration();
  rms.monitor.residual_rms_mm = 0.15;
  EXPECT_TRUE(Has(CheckCalibration(rms, "c"), "dot-residual"));
}

TEST(QualityCheck, MissingDotsHighReprojectionAndDroppedViewsAreWarnings) {
  calib::SessionCalibration c = GoodCalibration();
  for (int q = 0; q < 4; ++q) c.monitor.dots[q].residual_mm = -1;  // 4 of 36 > 5%
  c.camera.rms_px = 1.7;
  for (int v = 0; v < 3; ++v) {
    c.camera.views[v].used = false;
    c.camera.views[v].dropped_because = "board not found";
  }
  c.sample_plane.rms_px = 2.5;
  const auto warnings = CheckCalibration(c, "calibration.json");
  EXPECT_EQ(Checks(warnings), (std::vector<std::string>{"dots-missing", "camera-rms", "views-dropped", "sample-plane-rms"}));
  EXPECT_NE(Find(warnings, "dots-missing").figures.find("4 of 36 dots not found"), std::string::npos);
  EXPECT_NE(Find(warnings, "camera-rms").figures.find("1.700 px"), std::string::npos);
  EXPECT_NE(Find(warnings, "views-dropped").figures.find("board/v00: board not found"), std::string::npos);
  // One missing dot of 36 and one dropped view of 8 are within the limits.
  calib::SessionCalibration few = GoodCalibration();
  few.monitor.dots[3].residual_mm = -1;
  few.camera.views[2].used = false;
  EXPECT_TRUE(CheckCalibration(few, "c").empty());
}

}  // namespace
}  // namespace svbtdf::process
