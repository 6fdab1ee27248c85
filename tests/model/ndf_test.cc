// Properties every analytic NDF must have: projected-area normalisation, the Smith projected-area
// condition, a visible-normal sampler that matches its density, and the Ellipsoid NDF's reduction
// to GGX.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>

#include "sampling_check.h"
#include "svbtdf/common/error.h"
#include "svbtdf/model/ellipsoid_ndf.h"
#include "svbtdf/model/ggx.h"
#include "svbtdf/model/ndf_factory.h"

namespace svbtdf::model {
namespace {

struct NdfCase {
  const char* label;
  std::string name;
  AnalyticNdfParams params;
  bool exact_smith;  // G1 satisfies the projected-area condition with equality
};

std::vector<NdfCase> Cases() {
  std::vector<NdfCase> cases;
  for (const char* name : {"ggx", "beckmann"}) {
    for (double alpha : {0.05, 0.3, 1.0}) {
      AnalyticNdfParams p;
      p.alpha_x = alpha;
      p.alpha_y = 0.6 * alpha;
      cases.push_back({name, name, p, true});
    }
  }
  AnalyticNdfParams rotated;
  rotated.alpha_x = 0.4;
  rotated.alpha_y = 0.1;
  rotated.theta_z = 0.7;
  cases.push_back({"ellipsoid rotated", "ellipsoid", rotated, true});
  AnalyticNdfParams skewed = rotated;
  skewed.theta_x = 0.3;
  skewed.theta_y = -0.2;
  cases.push_back({"ellipsoid skewed", "ellipsoid", skewed, false});
  AnalyticNdfParams narrow_skewed = skewed;
  narrow_skewed.alpha_x = 0.08;
  narrow_skewed.alpha_y = 0.05;
  cases.push_back({"ellipsoid narrow skewed", "ellipsoid", narrow_skewed, false});
  for (double kappa : {5.0, 200.0, 2000.0}) {
    AnalyticNdfParams vmf;
    vmf.kappa = kappa;
    vmf.mean = Vec3(0.2, -0.1, 1.0).normalized();  // tilted
    vmf.alpha_x = 1.0 / std::sqrt(kappa);           // its angular width, for the sampler check's bins
    cases.push_back({"vmf tilted", "vmf", vmf, false});
  }
  return cases;
}

// Integral over the upper hemisphere in polar coordinates about `center` with radial nodes
// concentrated near it (r = pi s^2), so narrow lobes are resolved.
double IntegrateAround(const std::function<double(const Vec3&)>& f, const Vec3& center, int n_radial = 1500,
                       int n_phi = 256) {
  Vec3 t, b;
  OrthonormalBasis(center, &t, &b);
  double sum = 0;
  for (int a = 0; a < n_radial; ++a) {
    const double s = (a + 0.5) / n_radial, r = kPi * s * s, dr = 2 * kPi * s;
    for (int k = 0; k < n_phi; ++k) {
      const double phi = kTwoPi * (k + 0.5) / n_phi;
      const Vec3 d = std::cos(r) * center + std::sin(r) * (std::cos(phi) * t + std::sin(phi) * b);
      if (d.z() > 0) sum += f(d) * std::sin(r) * dr;
    }
  }
  return sum / n_radial * kTwoPi / n_phi;
}

// The lobe's mode, found on a coarse grid, to centre the quadrature on.
Vec3 Mode(const Ndf& ndf) {
  Vec3 best = Vec3::UnitZ();
  for (double theta = 0; theta < 1.5; theta += 0.01) {
    for (double phi = 0; phi < kTwoPi; phi += 0.05) {
      const Vec3 d = SphericalDirection(theta, phi);
      if (ndf.D(d) * d.z() > ndf.D(best) * best.z()) best = d;
    }
  }
  return best;
}

TEST(Ndf, ProjectedAreaNormalisation) {
  for (const NdfCase& c : Cases()) {
    const auto ndf = MakeAnalyticNdf(c.name, c.params);
    const double integral = IntegrateAround([&](const Vec3& h) { return ndf->D(h) * h.z(); }, Mode(*ndf));
    EXPECT_NEAR(integral, 1.0, 1e-3) << c.label << " alpha " << c.params.alpha_x;
  }
}

TEST(Ndf, SmithProjectedAreaCondition) {
  for (const NdfCase& c : Cases()) {
    const auto ndf = MakeAnalyticNdf(c.name, c.params);
    const Vec3 mode = Mode(*ndf);
    for (double theta : {0.0, 0.6, 1.2}) {
      const Vec3 v = SphericalDirection(theta, 0.8);
      const double visible = IntegrateAround(
          [&](const Vec3& h) { return ndf->G1(v, h) * std::max(0.0, v.dot(h)) * ndf->D(h); }, mode);
      if (c.exact_smith) {
        EXPECT_NEAR(visible, v.z(), 1e-3) << c.label << " alpha " << c.params.alpha_x << " theta " << theta;
      } else {
        EXPECT_LE(visible, v.z() * (1 + 1e-3)) << c.label << " theta " << theta;
      }
    }
  }
}

TEST(Ndf, VisibleNormalSamplersMatchTheirDensity) {
  for (const NdfCase& c : Cases()) {
    const auto ndf = MakeAnalyticNdf(c.name, c.params);
    for (double theta : {0.2, 1.0}) {
      const Vec3 v = SphericalDirection(theta, 2.0);
      const int resolution = c.params.alpha_x < 0.1 ? 64 : 16;  // narrow lobes need finer bins
      const testing::SamplerCheck check = testing::CheckSampler(*ndf, v, 200000, 17, resolution);
      EXPECT_TRUE(check.Passes()) << c.label << " alpha " << c.params.alpha_x << " theta " << theta << ": chi2 "
                                  << check.chi2 << " over " << check.bins << " bins";
      EXPECT_NEAR(check.pdf_integral, 1.0, 5e-3) << c.label;
      EXPECT_LT(check.max_pdf_mismatch, 1e-9) << c.label;
      EXPECT_LT(check.max_weight_mismatch, 1e-9) << c.label;
      EXPECT_LE(check.max_weight, 1.0 + 1e-9) << c.label;
    }
  }
}

TEST(Ndf, ExactSamplersHaveUnitWeights) {
  for (const char* name : {"ggx", "beckmann"}) {
    AnalyticNdfParams p;
    p.alpha_x = 0.4;
    p.alpha_y = 0.2;
    const auto ndf = MakeAnalyticNdf(name, p);
    std::mt19937_64 rng(2);
    std::uniform_real_distribution<double> u(0, 1);
    for (int k = 0; k < 2000; ++k) {
      const Vec3 v = SphericalDirection(1.4 * u(rng), kTwoPi * u(rng));
      const NormalSample s = ndf->SampleVisibleNormal(v, Vec2(u(rng), u(rng)));
      EXPECT_NEAR(s.weight, 1.0, 1e-9) << name;
    }
  }
}

TEST(Ndf, EllipsoidWithoutSkewIsRotatedGgx) {
  const double alpha_x = 0.35, alpha_y = 0.12, theta_z = 0.6;
  const EllipsoidNdf ellipsoid(alpha_x, alpha_y, 0.0, 0.0, theta_z);
  const GgxNdf ggx(alpha_x, alpha_y);
  // The ellipsoid's matrix A = S Rz(theta_z) maps h to S (Rz h): GGX evaluated at Rz(theta_z) h.
  const Mat3 rotate = Eigen::AngleAxisd(theta_z, Vec3::UnitZ()).toRotationMatrix();
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> u(0, 1);
  for (int k = 0; k < 2000; ++k) {
    const Vec3 h = SphericalDirection(1.5 * u(rng), kTwoPi * u(rng));
    const Vec3 v = SphericalDirection(1.5 * u(rng), kTwoPi * u(rng));
    EXPECT_NEAR(ellipsoid.D(h), ggx.D(rotate * h), 1e-12 * ggx.D(rotate * h));
    if (v.dot(h) > 0) {
      EXPECT_NEAR(ellipsoid.G1(v, h), ggx.G1(rotate * v, rotate * h), 1e-12);
    }
  }
}

TEST(Ndf, MaskingIsABoundedIndicatorOfFrontFacingFacets) {
  for (const NdfCase& c : Cases()) {
    const auto ndf = MakeAnalyticNdf(c.name, c.params);
    std::mt19937_64 rng(6);
    std::uniform_real_distribution<double> u(0, 1);
    for (int k = 0; k < 1000; ++k) {
      const Vec3 h = SphericalDirection(1.5 * u(rng), kTwoPi * u(rng));
      const Vec3 v = SphericalDirection(1.55 * u(rng), kTwoPi * u(rng));
      const double g = ndf->G1(v, h);
      EXPECT_GE(g, 0.0);
      EXPECT_LE(g, 1.0);
      if (v.dot(h) <= 0) {
        EXPECT_EQ(g, 0.0);
      }
      EXPECT_EQ(ndf->G1(-v, h), g) << "a direction below the surface is side-adjusted";
    }
  }
}

TEST(Ndf, FactoryRejectsBadParameters) {
  AnalyticNdfParams p;
  p.alpha_x = -0.1;
  EXPECT_THROW(MakeAnalyticNdf("ggx", p), common::Error);
  p.alpha_x = 0.2;
  p.alpha_y = 0.0;
  EXPECT_THROW(MakeAnalyticNdf("beckmann", p), common::Error);
  p.alpha_y = 0.2;
  p.theta_x = std::nan("");
  EXPECT_THROW(MakeAnalyticNdf("ellipsoid", p), common::Error);
  EXPECT_THROW(MakeAnalyticNdf("cauchy", AnalyticNdfParams{}), common::Error);
  AnalyticNdfParams vmf;
  vmf.kappa = 0.0;
  EXPECT_THROW(MakeAnalyticNdf("vmf", vmf), common::Error);
  vmf.kappa = 10.0;
  vmf.mean = Vec3(1.0, 0.0, -0.1);
  EXPECT_THROW(MakeAnalyticNdf("vmf", vmf), common::Error);
}

}  // namespace
}  // namespace svbtdf::model

namespace svbtdf::model {
namespace {

// A sampler that draws from GGX(0.3) but reports the density of GGX(0.33): the chi-square check
// must notice. Guards the check above against being vacuous.
class MismatchedSampler final : public Ndf {
 public:
  std::string name() const override { return "mismatched"; }
  double D(const Vec3& h) const override { return reported_.D(h); }
  double G1(const Vec3& v, const Vec3& h) const override { return reported_.G1(v, h); }
  NormalSample SampleVisibleNormal(const Vec3& v, const Vec2& u) const override {
    NormalSample s = drawn_.SampleVisibleNormal(v, u);
    s.pdf = reported_.VisibleNormalPdf(v, s.h);
    return s;
  }
  double VisibleNormalPdf(const Vec3& v, const Vec3& h) const override { return reported_.VisibleNormalPdf(v, h); }
  std::unique_ptr<Ndf> Clone() const override { return std::make_unique<MismatchedSampler>(); }

 private:
  GgxNdf drawn_{0.3}, reported_{0.33};
};

TEST(Ndf, TheSamplerCheckDetectsATenPercentRoughnessMismatch) {
  const testing::SamplerCheck check = testing::CheckSampler(MismatchedSampler(), SphericalDirection(0.5, 1.0), 200000, 3);
  EXPECT_FALSE(check.Passes()) << "chi2 " << check.chi2 << " over " << check.bins << " bins";
}

}  // namespace
}  // namespace svbtdf::model
