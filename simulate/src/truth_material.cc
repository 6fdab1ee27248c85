#include "svbtdf/simulate/truth_material.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "svbtdf/common/error.h"
#include "svbtdf/common/random.h"

namespace svbtdf::simulate {
namespace {


// Uniform [0, 1) value attached to an integer lattice point.
double LatticeValue(int64_t ix, int64_t iy, uint64_t seed) {
  const uint64_t h = common::SplitMix64(common::SplitMix64(seed) ^ common::SplitMix64(static_cast<uint64_t>(ix) * 0x632be59bd9b4e019ULL) ^
                          static_cast<uint64_t>(iy) * 0x85157af5ULL);
  return static_cast<double>(h >> 11) * 0x1.0p-53;
}

// Smooth value noise in [0, 1): bicubic-smoothstep interpolation of lattice values.
double ValueNoise(double x, double y, uint64_t seed) {
  const double fx = std::floor(x), fy = std::floor(y);
  const auto ix = static_cast<int64_t>(fx), iy = static_cast<int64_t>(fy);
  auto smooth = [](double t) { return t * t * (3.0 - 2.0 * t); };
  const double tx = smooth(x - fx), ty = smooth(y - fy);
  const double a = LatticeValue(ix, iy, seed), b = LatticeValue(ix + 1, iy, seed);
  const double c = LatticeValue(ix, iy + 1, seed), d = LatticeValue(ix + 1, iy + 1, seed);
  return (a + (b - a) * tx) + ((c + (d - c) * tx) - (a + (b - a) * tx)) * ty;
}

// Two octaves of noise, in [0, 1).
double Fractal(double x, double y, uint64_t seed) {
  return 0.65 * ValueNoise(x, y, seed) + 0.35 * ValueNoise(2.1 * x + 5.3, 2.1 * y + 1.7, seed + 1);
}

double SmoothStep(double edge0, double edge1, double x) {
  const double t = std::clamp((x - edge0) / (edge1 - edge0), 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

double Mix(double a, double b, double t) { return a + (b - a) * t; }

// u, v in [0, 1] across the sample (v = 0 at row 0); `aspect` = height / width.
using PatternFunction = TruthTexel (*)(double u, double v, double aspect, uint64_t seed);

TruthTexel SmoothPattern(double u, double v, double aspect, uint64_t seed) {
  TruthTexel t;
  const double n = Fractal(3.0 * u, 3.0 * v * aspect, seed);
  t.ndf.alpha_x = Mix(0.2, 0.4, n);
  t.ndf.alpha_y = t.ndf.alpha_x * Mix(0.8, 1.25, Fractal(2.0 * u + 7.0, 2.0 * v + 3.0, seed + 10));
  t.alpha = Mix(0.35, 0.7, v);
  t.shadowing_roughness = 0.2;
  t.k_s = {Mix(0.85, 0.95, u), 0.9, Mix(0.95, 0.8, u)};
  t.rho_d = {0.01, 0.01, 0.01};
  return t;
}

TruthTexel GridSheetPattern(double u, double v, double aspect, uint64_t seed) {
  TruthTexel t;
  // A plastic sheet with an embossed grid: 12 cells across, lines 15% of a cell wide. Inside the
  // cells the micro-grooves run along y (sharp in x), on the lines along x.
  const double cells = 12.0;
  auto line = [](double w) {
    const double f = w - std::floor(w);
    return 1.0 - SmoothStep(0.06, 0.09, std::min(f, 1.0 - f));
  };
  const double on_line = std::max(line(cells * u), line(cells * v * aspect));
  const double wobble = Mix(0.9, 1.1, Fractal(6.0 * u, 6.0 * v * aspect, seed));
  t.ndf.alpha_x = Mix(0.05, 0.40, on_line) * wobble;
  t.ndf.alpha_y = Mix(0.40, 0.05, on_line) * wobble;
  t.alpha = Mix(0.6, 0.4, on_line);
  t.shadowing_roughness = 0.2;
  t.k_s = {0.92, 0.93, 0.95};
  t.rho_d = {0.002, 0.002, 0.002};
  return t;
}

TruthTexel LeafGlassPattern(double u, double v, double aspect, uint64_t seed) {
  TruthTexel t;
  // Frosted leaves on clear glass: a few rotated pointed ellipses with soft edges.
  double leaf = 0.0;
  for (int k = 0; k < 7; ++k) {
    const double cx = 0.15 + 0.7 * LatticeValue(k, 1, seed);
    const double cy = 0.15 + 0.7 * LatticeValue(k, 2, seed);
    const double angle = model::kPi * LatticeValue(k, 3, seed);
    const double length = 0.12 + 0.12 * LatticeValue(k, 4, seed);
    const double dx = u - cx, dy = (v - cy) * aspect;
    const double a = std::cos(angle) * dx + std::sin(angle) * dy;
    const double b = -std::sin(angle) * dx + std::cos(angle) * dy;
    // Lens-shaped leaf: width tapers to the tips.
    const double half_width = 0.35 * length * std::max(0.0, 1.0 - model::Square(a / length));
    const double inside = std::max(0.0, 1.0 - std::abs(b) / std::max(half_width, 1e-9));
    leaf = std::max(leaf, SmoothStep(0.0, 0.25, inside) * (std::abs(a) < length ? 1.0 : 0.0));
  }
  const double grain = Fractal(20.0 * u, 20.0 * v * aspect, seed + 5);
  t.ndf.alpha_x = Mix(0.04, Mix(0.3, 0.5, grain), leaf);
  t.ndf.alpha_y = t.ndf.alpha_x;
  t.alpha = Mix(0.5, 0.65, leaf);
  t.shadowing_roughness = Mix(0.1, 0.3, leaf);
  t.k_s = {0.95, 0.96, 0.95};
  t.rho_d = {Mix(0.0, 0.01, leaf), Mix(0.0, 0.01, leaf), Mix(0.0, 0.01, leaf)};
  return t;
}

TruthTexel RicePaperPattern(double u, double v, double aspect, uint64_t seed) {
  TruthTexel t;
  // Long fibres mostly along x: stretched noise, rougher across the fibres.
  const double fibre = Fractal(6.0 * u, 40.0 * v * aspect, seed);
  const double density = Fractal(4.0 * u + 11.0, 4.0 * v * aspect, seed + 3);
  t.ndf.alpha_x = Mix(0.25, 0.45, density);
  t.ndf.alpha_y = t.ndf.alpha_x * Mix(1.1, 1.6, fibre);
  t.alpha = Mix(0.45, 0.65, density);
  t.shadowing_roughness = 0.3;
  t.k_s = {Mix(0.75, 0.85, fibre), Mix(0.62, 0.72, fibre), Mix(0.40, 0.50, fibre)};
  const double diffuse = Mix(0.02, 0.05, density);
  t.rho_d = {diffuse, 0.85 * diffuse, 0.6 * diffuse};
  return t;
}

// A near-Lambertian transmitting diffuser (opal glass): a flat BTDF, rho_d only. A lab puts one
// in the holder to measure its monitor's emission profile (svbtdf calibrate-emission). 0.1 1/sr
// is about an opal glass's: a third of the light through, spread over the hemisphere.
TruthTexel DiffuserPattern(double, double, double, uint64_t) {
  TruthTexel t;
  t.ndf.alpha_x = t.ndf.alpha_y = 0.5;  // no refractive term (k_s = 0): only for the dot quadrature
  t.alpha = 0.5;
  t.shadowing_roughness = 0.0;
  t.k_s = {0.0, 0.0, 0.0};
  t.rho_d = {0.1, 0.1, 0.1};
  return t;
}

PatternFunction FindPattern(const std::string& name) {
  if (name == "smooth") return SmoothPattern;
  if (name == "grid-sheet") return GridSheetPattern;
  if (name == "leaf-glass") return LeafGlassPattern;
  if (name == "rice-paper") return RicePaperPattern;
  if (name == "diffuser") return DiffuserPattern;
  common::ThrowInvalidInput("pattern", "unknown truth pattern '" + name + "'",
                    "use smooth, grid-sheet, leaf-glass, rice-paper or diffuser");
}

}  // namespace

std::vector<std::string> TruthPatternNames() {
  return {"smooth", "grid-sheet", "leaf-glass", "rice-paper", "diffuser"};
}

TruthMaterial::TruthMaterial(int texels_x, int texels_y, double eta, std::string ndf_name,
                             std::vector<TruthTexel> texels)
    : texels_x_(texels_x), texels_y_(texels_y), eta_(eta), ndf_name_(std::move(ndf_name)),
      texels_(std::move(texels)) {
  if (texels_x < 1 || texels_y < 1) {
    common::ThrowInvalidInput("truth material", "needs at least 1 x 1 texels");
  }
  if (texels_.size() != static_cast<size_t>(texels_x) * texels_y) {
    common::ThrowInvalidInput("truth material", "has " + std::to_string(texels_.size()) +
                      " texels, expected " + std::to_string(texels_x * texels_y));
  }
  if (!(eta > 1.0) || !std::isfinite(eta)) {
    common::ThrowInvalidInput("--eta", "must be > 1 (eta = n_slab / n_air), got " + std::to_string(eta));
  }
  ndfs_.reserve(texels_.size());
  models_.reserve(texels_.size());
  for (const TruthTexel& t : texels_) {
    if (!(t.alpha >= 0.0 && t.alpha <= 1.0)) {
      common::ThrowInvalidInput("truth material", "blend weight alpha outside [0, 1]");
    }
    ndfs_.push_back(model::MakeAnalyticNdf(ndf_name_, t.ndf));
    models_.emplace_back(eta_, t.shadowing_roughness > 0.0
                                   ? model::SmithShadowing::Ggx(t.shadowing_roughness)
                                   : model::SmithShadowing::None());
    // Asked for every dot that could change its rule: computed once here.
    if (ndf_name_ == "ggx") lobe_peaks_.push_back(ndfs_.back()->D(model::Vec3::UnitZ()));
  }
}

TruthMaterial TruthMaterial::FromPattern(const std::string& pattern, int texels_x, int texels_y,
                                         double eta, uint64_t seed) {
  const PatternFunction function = FindPattern(pattern);
  if (texels_x < 1 || texels_y < 1) {
    common::ThrowInvalidInput("truth material", "needs at least 1 x 1 texels");
  }
  const double aspect = static_cast<double>(texels_y) / texels_x;
  std::vector<TruthTexel> texels;
  texels.reserve(static_cast<size_t>(texels_x) * texels_y);
  for (int row = 0; row < texels_y; ++row) {
    for (int col = 0; col < texels_x; ++col) {
      texels.push_back(function((col + 0.5) / texels_x, (row + 0.5) / texels_y, aspect, seed));
    }
  }
  return TruthMaterial(texels_x, texels_y, eta, "ggx", std::move(texels));
}

model::Rgb TruthMaterial::Evaluate(int index, const model::Vec3& i, const model::Vec3& o) const {
  const TruthTexel& t = texels_[index];
  const double rho = models_[index].Rho(*ndfs_[index], t.alpha, i, o);
  return {t.k_s[0] * rho + t.rho_d[0], t.k_s[1] * rho + t.rho_d[1], t.k_s[2] * rho + t.rho_d[2]};
}

model::Rgb TruthMaterial::EvaluatePolarised(int index, const model::Vec3& i, const model::Vec3& o,
                                             const model::Vec3& field) const {
  const TruthTexel& t = texels_[index];
  const double rho = models_[index].Rho(*ndfs_[index], t.alpha, i, o, &field);
  return {t.k_s[0] * rho + t.rho_d[0], t.k_s[1] * rho + t.rho_d[1], t.k_s[2] * rho + t.rho_d[2]};
}

double TruthMaterial::LobeFraction(int index, const model::Vec3& i, const model::Vec3& o) const {
  if (lobe_peaks_.empty()) return 1.0;  // not GGX
  const model::Ndf& ndf = *ndfs_[index];
  const double peak = lobe_peaks_[index];
  double fraction = 0.0;
  for (const std::optional<model::Vec3>& h : models_[index].HalfVectors(i, o)) {
    if (h) fraction = std::max(fraction, ndf.D(*h) / peak);
  }
  return std::min(fraction, 1.0);
}

double TruthMaterial::MinRoughness(int index) const {
  const model::AnalyticNdfParams& p = texels_[index].ndf;
  return std::min(p.alpha_x, p.alpha_y);
}

}  // namespace svbtdf::simulate
