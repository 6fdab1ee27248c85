#include "svbtdf/report/texel_inspection.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "svbtdf/common/parallel.h"
#include "svbtdf/model/sg_lobe.h"
#include "svbtdf/report/page_data.h"
#include "svbtdf/simulate/truth_io.h"

namespace svbtdf::report {
namespace {

using model::Vec3;

std::string Float32Base64(const std::vector<float>& values) {
  std::string bytes(values.size() * sizeof(float), '\0');
  // little-endian, as JS's Float32Array reads it; an empty vector's data() may be null, which
  // memcpy must never be given even for zero bytes
  if (!values.empty()) std::memcpy(bytes.data(), values.data(), bytes.size());
  return Base64(bytes);
}

// Two unit vectors across `axis`.
void TangentFrame(const Vec3& axis, Vec3* t1, Vec3* t2) {
  const Vec3 helper = std::abs(axis.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  *t1 = axis.cross(helper).normalized();
  *t2 = axis.cross(*t1);
}

// The lobe's samples: directions (z < 0) with their solid angles, the specular luminance times
// |i.z| and its RGB sum (for the colour).
struct LobeSamples {
  std::vector<Vec3> directions;
  std::vector<double> values, weights;
  std::vector<std::array<double, 3>> specular_rgb;  // per direction, k_s rho |i.z| in RGB
  std::array<double, 3> rgb_sum{};
  double luminance_sum = 0;
  void Add(const fit::TexelBtdf& texel, const Vec3& o, const Vec3& i, double solid_angle) {
    if (!(i.z() < -1e-3)) return;
    const model::Rgb r = texel.Evaluate(i, o);
    const model::Rgb& rho_d = texel.params().rho_d;
    std::array<double, 3>& specular = specular_rgb.emplace_back();
    for (int c = 0; c < 3; ++c) specular[c] = std::max(0.0, r[c] - rho_d[c]) * -i.z();
    const double luminance = (specular[0] + specular[1] + specular[2]) / 3;
    directions.push_back(i);
    values.push_back(luminance);
    weights.push_back(solid_angle);
    for (int c = 0; c < 3; ++c) rgb_sum[c] += specular[c] * solid_angle;
    luminance_sum += luminance * solid_angle;
  }
};

// A gnomonic grid of side n around `axis` reaching `extent` (tangent of the half angle).
LobeSamples SamplesAround(const fit::TexelBtdf& texel, const Vec3& o, const Vec3& axis, double extent, int n) {
  Vec3 t1, t2;
  TangentFrame(axis, &t1, &t2);
  LobeSamples samples;
  const double step = 2 * extent / n;
  for (int b = 0; b < n; ++b) {
    for (int a = 0; a < n; ++a) {
      const double u = -extent + (a + 0.5) * step, v = -extent + (b + 0.5) * step;
      const double r2 = 1 + u * u + v * v;
      samples.Add(texel, o, (axis + u * t1 + v * t2).normalized(), step * step / (r2 * std::sqrt(r2)));
    }
  }
  return samples;
}

}  // namespace

TexelGrid MakeTexelGrid(int width, int height, int max_side) {
  TexelGrid grid;
  grid.cols = std::max(1, std::min(width, max_side));
  grid.rows = std::max(1, std::min(height, max_side));
  for (int c = 0; c < grid.cols; ++c) grid.x.push_back(static_cast<int>((c + 0.5) * width / grid.cols));
  for (int r = 0; r < grid.rows; ++r) grid.y.push_back(static_cast<int>((r + 0.5) * height / grid.rows));
  return grid;
}

int InspectionGridSide(int width, int height, int dots, int max_side, int64_t sample_budget) {
  const int by_budget = static_cast<int>(std::sqrt(static_cast<double>(sample_budget) / std::max(1, dots)));
  return std::max(1, std::min({max_side, std::max(width, height), by_budget}));
}

std::vector<Vec3> LobeViews() {
  const double s = std::sin(30 * model::kPi / 180), c = std::cos(30 * model::kPi / 180);
  return {Vec3(0, 0, 1), Vec3(s, 0, c), Vec3(0, s, c), Vec3(-s, 0, c), Vec3(0, -s, c)};
}

TexelLobe FitTexelLobe(const fit::TexelBtdf& texel, const Vec3& o) {
  constexpr size_t kMinSamples = 16;  // fewer: the lobe lies beyond the horizon, nothing to fit
  const LobeSamples coarse = SamplesAround(texel, o, -o, std::tan(75 * model::kPi / 180), 32);
  TexelLobe result;
  if (!(coarse.luminance_sum > 0) || coarse.directions.size() < kMinSamples) return result;
  model::SphericalGaussianFit fit = model::FitSphericalGaussian(coarse.directions, coarse.values, coarse.weights);
  const double extent = std::clamp(3 / std::sqrt(std::max(fit.lobe.sharpness, 1e-3)), 0.02, 1.5);
  LobeSamples fine = SamplesAround(texel, o, fit.lobe.axis, extent, 24);
  const bool refined = fine.luminance_sum > 0 && fine.directions.size() >= kMinSamples;
  if (refined) fit = model::FitSphericalGaussian(fine.directions, fine.values, fine.weights);
  const LobeSamples& shape = refined ? fine : coarse;
  result.lobe = fit.lobe;
  result.relative_l2 = fit.relative_l2;
  // Anisotropy: the second moments of the lobe across its axis (gnomonic coordinates).
  Vec3 t1, t2;
  TangentFrame(fit.lobe.axis, &t1, &t2);
  // The energy, not the fitted amplitude: a least-squares Gaussian misses the heavy tails of a
  // microfacet lobe (13% of the light on the tiny preset), which the picture would lose. The fine
  // grid integrates the lobe's core (the coarse one misses glossy lobes between its points), the
  // coarse one what lies beyond the fine window.
  result.energy_rgb = refined ? fine.rgb_sum : coarse.rgb_sum;
  if (refined) {
    for (size_t k = 0; k < coarse.directions.size(); ++k) {
      const Vec3& d = coarse.directions[k];
      const double along = d.dot(fit.lobe.axis);
      const Vec3 p = along > 0 ? Vec3(d / along - fit.lobe.axis) : Vec3::Zero();
      if (along > 0 && std::abs(p.dot(t1)) <= extent && std::abs(p.dot(t2)) <= extent) continue;  // inside the fine window
      for (int c = 0; c < 3; ++c) result.energy_rgb[c] += coarse.specular_rgb[k][c] * coarse.weights[k];
    }
  }
  double uu = 0, uv = 0, vv = 0, mass = 0;
  for (size_t k = 0; k < shape.directions.size(); ++k) {
    const Vec3& d = shape.directions[k];
    const double along = d.dot(fit.lobe.axis);
    if (along <= 0.05) continue;
    const Vec3 p = d / along - fit.lobe.axis;
    const double u = p.dot(t1), v = p.dot(t2), w = shape.values[k] * shape.weights[k];
    uu += w * u * u, uv += w * u * v, vv += w * v * v, mass += w;
  }
  if (!(mass > 0)) return result;
  const double mean = 0.5 * (uu + vv), half_gap = std::hypot(0.5 * (uu - vv), uv);
  const double wide = mean + half_gap, narrow = std::max(mean - half_gap, 1e-12);
  const double angle = 0.5 * std::atan2(2 * uv, uu - vv);
  const double aspect = std::clamp(std::sqrt(wide / narrow), 1.0, 10.0);  // ratio of the widths
  result.major = std::cos(angle) * t1 + std::sin(angle) * t2;
  result.sharpness_major = fit.lobe.sharpness / aspect;
  result.sharpness_minor = fit.lobe.sharpness * aspect;
  return result;
}

nlohmann::json InspectionData(const fit::Material& material, const fit::SliceStore* store,
                              const simulate::MaterialTruth* truth_parameters, const std::vector<int>& held_out,
                              const TexelGrid& grid, int threads) {
  const int dots = store ? static_cast<int>(store->geometry().dots.size()) : 0;
  const int cells = kInspectionNdfSide * kInspectionNdfSide;
  const size_t texels = static_cast<size_t>(grid.cols) * grid.rows;
  std::vector<float> measured(texels * dots, NAN), fitted(texels * dots, NAN);
  std::vector<uint8_t> ndf(texels * cells, kNdfOutside), true_ndf(truth_parameters ? texels * cells : 0, kNdfOutside);
  std::vector<float> residual(texels);
  const fit::MaterialEvaluator evaluator(material);
  // ln D over the disc of h seen from above, as bytes: 0 .. 254 for the top 8 units of ln D (a
  // byte is as fine as the colour ramp; float32 made the page 4 times larger at 600x600).
  const auto ln_d_picture = [&](const model::Ndf& d, uint8_t* out) {
    std::vector<double> ln_d(cells, NAN);
    double peak = -1e300;
    for (int py = 0; py < kInspectionNdfSide; ++py) {
      for (int px = 0; px < kInspectionNdfSide; ++px) {
        const double u = (px + 0.5) / kInspectionNdfSide * 2 - 1, v = 1 - (py + 0.5) / kInspectionNdfSide * 2;
        if (u * u + v * v >= 1) continue;
        ln_d[py * kInspectionNdfSide + px] = std::log(std::max(d.D(Vec3(u, v, std::sqrt(1 - u * u - v * v))), 1e-30));
        peak = std::max(peak, ln_d[py * kInspectionNdfSide + px]);
      }
    }
    for (int c = 0; c < cells; ++c) {
      if (std::isnan(ln_d[c])) continue;
      out[c] = static_cast<uint8_t>(std::lround(std::clamp((ln_d[c] - peak + 8) / 8, 0.0, 1.0) * (kNdfOutside - 1)));
    }
  };
  common::ParallelFor(static_cast<int64_t>(texels), threads, 4, [&](int64_t begin, int64_t end) {
    std::vector<float> samples;
    for (int64_t k = begin; k < end; ++k) {
      const int x = grid.x[k % grid.cols], y = grid.y[k / grid.cols];
      residual[k] = material.residual.at(x, y);
      const fit::TexelBtdf texel = evaluator.Texel(x, y);
      ln_d_picture(texel.ndf(), &ndf[k * cells]);
      if (truth_parameters) ln_d_picture(*truth_parameters->TexelNdf(x, y), &true_ndf[k * cells]);
      if (!store) continue;
      const int64_t index = static_cast<int64_t>(y) * material.width + x;
      store->ReadSamples(index, &samples);
      const Vec3 o = store->geometry().View(index);
      for (int q = 0; q < dots; ++q) {
        const float* rgb = &samples[static_cast<size_t>(q) * 3];
        if (std::isfinite(rgb[0]) && std::isfinite(rgb[1]) && std::isfinite(rgb[2])) {
          measured[k * dots + q] = (rgb[0] + rgb[1] + rgb[2]) / 3;
        }
        fitted[k * dots + q] = static_cast<float>(model::Luminance(texel.Evaluate(store->geometry().Light(index, q), o)));
      }
    }
  });
  nlohmann::json dot_positions = nlohmann::json::array(), texel_centres = nlohmann::json::array();
  if (store) {
    for (const Vec3& p : store->geometry().dots) dot_positions.push_back({p.x(), p.y(), p.z()});
    for (size_t k = 0; k < texels; ++k) {
      const Vec3 centre = store->geometry().TexelCentre(static_cast<int64_t>(grid.y[k / grid.cols]) * material.width + grid.x[k % grid.cols]);
      texel_centres.push_back({centre.x(), centre.y()});
    }
  }
  return {{"cols", grid.cols}, {"rows", grid.rows}, {"x", grid.x}, {"y", grid.y}, {"dots", dots},
          {"held_out", held_out}, {"dot_positions", dot_positions}, {"texel_centres", texel_centres},
          {"measured", Float32Base64(measured)}, {"fitted", Float32Base64(fitted)},
          {"residual", Float32Base64(residual)}, {"ndf_side", kInspectionNdfSide}, {"ndf", Base64(std::string(ndf.begin(), ndf.end()))},
          {"true_ndf", Base64(std::string(true_ndf.begin(), true_ndf.end()))}};
}

nlohmann::json LobeData(const fit::Material& material, const TexelGrid& grid, int threads) {
  const std::vector<Vec3> views = LobeViews();
  constexpr int kPerView = 11;
  const size_t stride = views.size() * kPerView + 3;
  const size_t texels = static_cast<size_t>(grid.cols) * grid.rows;
  std::vector<float> data(texels * stride, 0.0f);
  std::vector<double> error(texels, 0.0);
  const fit::MaterialEvaluator evaluator(material);
  common::ParallelFor(static_cast<int64_t>(texels), threads, 4, [&](int64_t begin, int64_t end) {
    for (int64_t k = begin; k < end; ++k) {
      const int x = grid.x[k % grid.cols], y = grid.y[k / grid.cols];
      const fit::TexelBtdf texel = evaluator.Texel(x, y);
      float* out = &data[k * stride];
      for (size_t v = 0; v < views.size(); ++v) {
        const TexelLobe lobe = FitTexelLobe(texel, views[v]);
        const Vec3 shift = lobe.lobe.axis + views[v];  // axis - (-o)
        const double values[kPerView] = {shift.x(), shift.y(), shift.z(), lobe.major.x(), lobe.major.y(), lobe.major.z(),
                                         lobe.sharpness_major, lobe.sharpness_minor,
                                         lobe.energy_rgb[0], lobe.energy_rgb[1], lobe.energy_rgb[2]};
        for (int j = 0; j < kPerView; ++j) out[v * kPerView + j] = static_cast<float>(values[j]);
        error[k] += lobe.relative_l2 / views.size();
      }
      for (int c = 0; c < 3; ++c) out[views.size() * kPerView + c] = static_cast<float>(texel.params().rho_d[c]);
    }
  });
  std::vector<double> sorted = error;
  std::sort(sorted.begin(), sorted.end());
  nlohmann::json view_list = nlohmann::json::array();
  for (const Vec3& v : views) view_list.push_back({v.x(), v.y(), v.z()});
  return {{"cols", grid.cols}, {"rows", grid.rows}, {"views", view_list}, {"per_view", kPerView},
          {"stride", stride}, {"width_m", material.width_m}, {"height_m", material.height_m},
          {"fit_relative_l2_median", sorted.empty() ? 0.0 : sorted[sorted.size() / 2]},
          {"data", Float32Base64(data)}};
}

}  // namespace svbtdf::report
