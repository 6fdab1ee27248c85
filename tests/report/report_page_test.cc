// report::WriteMaterialReport in process: the page and the figures it names, beside either kind
// of truth, and the folder and size rules.
#include "svbtdf/report/material_report.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <regex>
#include <set>

#include "material_from_truth.h"
#include "simulated_truths.h"
#include "small_material.h"
#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/image_io.h"
#include "svbtdf/simulate/truth.h"

namespace svbtdf::report {
namespace {
namespace fs = std::filesystem;

class ReportPage : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("svbtdf-report-page-" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Writes the material and its report; returns the figures the page names.
  std::set<std::string> Report(const fit::Material& material, const std::string& truth_folder = "") {
    fit::WriteMaterial(dir_ / "material", material);
    MaterialReportOptions options;
    options.material_folder = (dir_ / "material").string();
    options.out = dir_ / "report";
    options.truth_folder = truth_folder;
    WriteMaterialReport(options);
    const std::string html = common::ReadTextFile(dir_ / "report" / "index.html");
    std::set<std::string> figures;
    const std::regex image("<img src=\"([^\"]+)\">");
    for (auto it = std::sregex_iterator(html.begin(), html.end(), image); it != std::sregex_iterator(); ++it) {
      figures.insert((*it)[1]);
    }
    // The page's scripts and stylesheet count as files it names (the interactive parts, docs/report.md).
    const std::regex script("<(?:script src|link rel=\"stylesheet\" href)=\"([^\"]+)\"");
    for (auto it = std::sregex_iterator(html.begin(), html.end(), script); it != std::sregex_iterator(); ++it) {
      figures.insert((*it)[1]);
    }
    return figures;
  }

  // Every figure the page names was written, and nothing else beside the page.
  void ExpectFiguresWritten(const std::set<std::string>& figures) {
    size_t files = 0;
    for (const auto& entry : fs::directory_iterator(dir_ / "report")) {
      const std::string name = entry.path().filename().string();
      if (name == "index.html") continue;
      ++files;
      EXPECT_TRUE(figures.count(name)) << name << " is not on the page";
    }
    EXPECT_EQ(files, figures.size());
  }

  fs::path dir_;
};

TEST_F(ReportPage, NamesTheMaterialsFiguresAndWritesThem) {
  const std::set<std::string> figures = Report(SmallMaterial());
  for (const char* file : {"alpha.png", "shadowing.png", "k_s.png", "rho_d.png", "residual.png", "cluster.png", "ndf_0.png",
                           "three-bundle.js", "report.js", "report.css", "report-data.js", "report-texels.js", "report-lobes.js"}) {
    EXPECT_TRUE(figures.count(file)) << file;
  }
  EXPECT_FALSE(figures.count("alpha_truth.png"));
  ExpectFiguresWritten(figures);
  // Small maps are enlarged to at least 256 pixels by replication (3x2 -> 255x170 at scale 85).
  const common::CameraImage alpha = common::ReadCameraImage(dir_ / "report" / "alpha.png");
  EXPECT_EQ(alpha.width, 3 * 85);
  EXPECT_EQ(alpha.height, 2 * 85);
  EXPECT_EQ(alpha.channels, 3);
  EXPECT_EQ(alpha.bits_per_sample, 8);
}

// One simulation per test process (15-25 s each): the size check shares the analytic truth.
TEST_F(ReportPage, ShowsAnAnalyticTruthsMapsAndNdfsAndRefusesATruthOfAnotherSize) {
  const fs::path truth_folder = SimulatedTruths::TruthFolder("model");
  const std::set<std::string> figures = Report(MaterialFromTruth(*simulate::ReadTruth(truth_folder).parameters()), truth_folder);
  for (const char* file : {"alpha_truth.png", "alpha_error.png", "rho_d_truth.png", "rho_d_error.png", "k_s_error.png",
                           "ndf_0_truth.png", "ndf_11.png"}) {
    EXPECT_TRUE(figures.count(file)) << file;
  }
  EXPECT_FALSE(figures.count("slab_material_truth.png"));
  ExpectFiguresWritten(figures);

  fit::WriteMaterial(dir_ / "small", SmallMaterial());
  MaterialReportOptions options;
  options.material_folder = (dir_ / "small").string();
  options.out = dir_ / "other";
  options.truth_folder = truth_folder.string();
  try {
    WriteMaterialReport(options);
    ADD_FAILURE() << "a 3x2 material was reported beside a 32x32 truth";
  } catch (const common::Error& e) {
    EXPECT_EQ(e.subject(), options.material_folder);
    EXPECT_NE(e.problem().find("3x2"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir_ / "other"));  // nothing written before the inputs were checked
}

TEST_F(ReportPage, ShowsAMonteCarloTruthsRhoDAndSlabMaterials) {
  const fs::path truth_folder = SimulatedTruths::TruthFolder("montecarlo");
  const simulate::Truth truth = simulate::ReadTruth(truth_folder);
  const std::set<std::string> figures = Report(SmallMaterial(truth.width(), truth.height()), truth_folder.string());
  EXPECT_TRUE(figures.count("rho_d_truth.png"));
  EXPECT_TRUE(figures.count("slab_material_truth.png"));
  // It has no alpha and no NDF to show.
  for (const char* file : {"alpha_truth.png", "alpha_error.png", "ndf_0_truth.png"}) EXPECT_FALSE(figures.count(file)) << file;
  ExpectFiguresWritten(figures);
  const std::string html = common::ReadTextFile(dir_ / "report" / "index.html");
  EXPECT_NE(html.find("Monte Carlo truth has no alpha"), std::string::npos);
  EXPECT_NE(html.find("frosted"), std::string::npos);  // the slab materials are listed
}

TEST_F(ReportPage, RefusesMissingRendersOrGltfNamingThemBeforeWritingAnything) {
  fit::WriteMaterial(dir_ / "material", SmallMaterial());
  for (const bool renders : {true, false}) {
    MaterialReportOptions options;
    options.material_folder = (dir_ / "material").string();
    options.out = dir_ / "report";
    (renders ? options.renders_folder : options.gltf_file) = (dir_ / "missing").string();
    try {
      WriteMaterialReport(options);
      ADD_FAILURE() << "a missing " << (renders ? "--renders" : "--gltf") << " was accepted";
    } catch (const common::Error& e) {
      EXPECT_EQ(e.subject(), (dir_ / "missing").string());
    }
    EXPECT_FALSE(fs::exists(dir_ / "report"));
  }
}

TEST_F(ReportPage, RefusesAFolderThatHoldsSomething) {
  Report(SmallMaterial());
  MaterialReportOptions options;
  options.material_folder = (dir_ / "material").string();
  options.out = dir_ / "report";
  try {
    WriteMaterialReport(options);
    ADD_FAILURE() << "the report wrote into a folder that holds a report";
  } catch (const common::Error& e) {
    EXPECT_EQ(e.subject(), options.out.string());
    EXPECT_NE(e.problem().find("is not empty"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace svbtdf::report
