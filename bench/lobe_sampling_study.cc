// How well the fit recovers alpha when the dots sample a narrow lobe sparsely: the study behind
// the lobe-undersampled quality check (docs/quality.md, "How many dots across a lobe"). Not a
// speed benchmark: it prints accuracy, and the fit's time as the last figure.
//
// A store is synthesised by tests/support/analytic_store.h (its rig: the camera 45 degrees above
// an 8 cm sample, a square grid of DOTS x DOTS dots 4 cm behind it; 1% noise; its alpha, 0.3 to
// 0.7 across the sample) with GGX lobes ACROSS along x and 0.40 along y, eta 1.4; every texel is
// fitted on its own (no clustering).
//
//   lobe_sampling_study ACROSS DOTS [TEXELS_PER_SIDE=6] [NDF_RESOLUTION=32]

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <unistd.h>

#include "analytic_store.h"
#include "svbtdf/fit/fit_material.h"
#include "svbtdf/fit/quality.h"

namespace {

using namespace svbtdf;

constexpr double kEta = 1.4;

double Median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: lobe_sampling_study ACROSS DOTS [TEXELS_PER_SIDE=6] [NDF_RESOLUTION=32]\n");
    return 2;
  }
  const double across = std::atof(argv[1]);
  const int dots = std::atoi(argv[2]);
  const int side = argc > 3 ? std::atoi(argv[3]) : 6;
  const std::filesystem::path folder =
      std::filesystem::temp_directory_path() / ("svbtdf-lobe-sampling-" + std::to_string(::getpid()));
  testing::AnalyticMaterial truth{side, side};
  truth.eta = kEta;
  truth.across = across;
  truth.along = 0.40;
  testing::WriteAnalyticStore(folder, truth, dots, 0.01, kEta);
  const fit::SliceStore store = fit::SliceStore::Open(folder);
  std::vector<double> dots_across;
  for (int64_t t = 0; t < store.geometry().num_texels(); ++t) dots_across.push_back(fit::DotsAcrossLobe(store.MakeTexelSlice(t)));

  fit::FitMaterialOptions options;
  options.representative_fraction = 1.0;
  options.progress = false;
  if (argc > 4) options.ndf_resolution = std::atoi(argv[4]);
  const auto start = std::chrono::steady_clock::now();
  const fit::Material fitted = fit::FitMaterial(store, options);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::filesystem::remove_all(folder);

  std::vector<double> alpha_error, residual;
  for (int y = 0; y < side; ++y) {
    for (int x = 0; x < side; ++x) {
      alpha_error.push_back(std::abs(fitted.alpha.at(x, y) - truth.Params(x, y).alpha));
      residual.push_back(fitted.residual.at(x, y));
    }
  }
  const auto within = std::count_if(alpha_error.begin(), alpha_error.end(), [](double e) { return e <= 0.05; });
  std::printf("GGX %.2f across, %d x %d dots, hemicube %d: dots across min %.2f median %.2f; alpha within 0.05 on "
              "%.0f%%, median |alpha error| %.3f, median residual %.3f; fit %.1f s\n",
              across, dots, dots, options.ndf_resolution, *std::min_element(dots_across.begin(), dots_across.end()),
              Median(dots_across), 100.0 * within / alpha_error.size(), Median(alpha_error), Median(residual), seconds);
}
