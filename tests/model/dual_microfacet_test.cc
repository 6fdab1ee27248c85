// Tests of Fresnel, shadowing and the dual-microfacet configurations against the physical
// properties every implementation must have (shared/docs/dual-microfacet-notes.md, "Checks").
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <functional>
#include <memory>
#include <optional>
#include <random>

#include "svbtdf/common/error.h"
#include "svbtdf/model/dual_microfacet.h"
#include "svbtdf/model/fresnel.h"
#include "svbtdf/model/ndf_factory.h"
#include "svbtdf/model/shadowing.h"

namespace svbtdf::model {
namespace {

std::unique_ptr<Ndf> Ggx(double alpha_x, double alpha_y) {
  AnalyticNdfParams params;
  params.alpha_x = alpha_x;
  params.alpha_y = alpha_y;
  return MakeAnalyticNdf("ggx", params);
}

// A skewed NDF (an ellipsoid tilted off the normal): D(-h.x, -h.y, h.z) != D(h), so reciprocity
// tests catch sign errors that a symmetric NDF would hide.
std::unique_ptr<Ndf> SkewedNdf() {
  AnalyticNdfParams params;
  params.alpha_x = 0.3;
  params.alpha_y = 0.15;
  params.theta_x = 0.25;
  params.theta_y = -0.15;
  params.theta_z = 0.4;
  return MakeAnalyticNdf("ellipsoid", params);
}

// D'(h) = D(-h.x, -h.y, h.z): the NDF of an interface seen from the other side of the slab.
class MirroredNdf final : public Ndf {
 public:
  explicit MirroredNdf(const Ndf& base) : base_(base.Clone()) {}
  std::string name() const override { return "mirrored-" + base_->name(); }
  double D(const Vec3& h) const override { return base_->D(Mirror(h)); }
  double G1(const Vec3& v, const Vec3& h) const override { return base_->G1(Mirror(v), Mirror(h)); }
  NormalSample SampleVisibleNormal(const Vec3& v, const Vec2& u) const override {
    NormalSample s = base_->SampleVisibleNormal(Mirror(v), u);
    s.h = Mirror(s.h);
    return s;
  }
  double VisibleNormalPdf(const Vec3& v, const Vec3& h) const override {
    return base_->VisibleNormalPdf(Mirror(v), Mirror(h));
  }
  std::unique_ptr<Ndf> Clone() const override { return std::make_unique<MirroredNdf>(*base_); }

 private:
  static Vec3 Mirror(const Vec3& v) { return {-v.x(), -v.y(), v.z()}; }
  std::unique_ptr<Ndf> base_;
};

Vec3 LightDirection(double theta_deg, double phi_deg) {
  return FlipZ(SphericalDirection(theta_deg * kPi / 180, phi_deg * kPi / 180));
}

// Integral of f(o) o.z over the part of the upper hemisphere within `radius` of `center`, in
// polar coordinates about the centre with radial nodes r = radius s^2 (s uniform), so that the
// narrow lobes around the centre are resolved finely and the rest of the hemisphere coarsely.
// The midpoint rule in s; directions below the horizon contribute nothing.
double IntegrateProjectedAround(const std::function<double(const Vec3&)>& f, const Vec3& center,
                                double radius, int n_radial, int n_phi) {
  Vec3 t, b;
  OrthonormalBasis(center, &t, &b);
  double sum = 0.0;
  for (int a = 0; a < n_radial; ++a) {
    const double s = (a + 0.5) / n_radial;
    const double r = radius * s * s;
    const double dr_ds = 2.0 * radius * s;
    for (int k = 0; k < n_phi; ++k) {
      const double phi = kTwoPi * (k + 0.5) / n_phi;
      const Vec3 o = std::cos(r) * center + std::sin(r) * (std::cos(phi) * t + std::sin(phi) * b);
      if (o.z() <= 0) continue;
      sum += f(o) * o.z() * std::sin(r) * dr_ds;
    }
  }
  return sum * (1.0 / n_radial) * (kTwoPi / n_phi);
}

// Solid angle of a small spherical polygon (vertices in order) measured in the tangent plane of
// its centroid: accurate to O(size^2) relative, enough for 1e-4-sized cones.
double SmallPolygonSolidAngle(const std::vector<Vec3>& vertices) {
  Vec3 center = Vec3::Zero();
  for (const Vec3& v : vertices) center += v;
  center.normalize();
  Vec3 t, b;
  OrthonormalBasis(center, &t, &b);
  double area = 0.0;
  for (size_t k = 0; k < vertices.size(); ++k) {
    const Vec3& p = vertices[k];
    const Vec3& q = vertices[(k + 1) % vertices.size()];
    const Vec2 p2(p.dot(t) / p.dot(center), p.dot(b) / p.dot(center));
    const Vec2 q2(q.dot(t) / q.dot(center), q.dot(b) / q.dot(center));
    area += p2.x() * q2.y() - q2.x() * p2.y();
  }
  return 0.5 * std::abs(area);
}

// |d omega_h / d omega_o| by perturbing o on a tiny cone and measuring the cone of h.
double FiniteDifferenceJacobian(const std::function<Vec3(const Vec3&)>& half_vector, const Vec3& o) {
  constexpr int kVertices = 64;
  constexpr double kRadius = 1e-4;
  Vec3 t, b;
  OrthonormalBasis(o, &t, &b);
  std::vector<Vec3> cone_o, cone_h;
  for (int k = 0; k < kVertices; ++k) {
    const double phi = kTwoPi * k / kVertices;
    const Vec3 v = (o + kRadius * (std::cos(phi) * t + std::sin(phi) * b)).normalized();
    cone_o.push_back(v);
    cone_h.push_back(half_vector(v));
  }
  return SmallPolygonSolidAngle(cone_h) / SmallPolygonSolidAngle(cone_o);
}

// ---------------------------------------------------------------------------------------------
TEST(Fresnel, NormalIncidenceMatchesTheClosedForm) {
  for (double eta : {1.1, 1.33, 1.5, 2.4}) {
    EXPECT_NEAR(FresnelDielectric(1.0, eta), Square((eta - 1) / (eta + 1)), 1e-15);
    EXPECT_NEAR(FresnelDielectric(-1.0, eta), Square((eta - 1) / (eta + 1)), 1e-15);
  }
}

TEST(Fresnel, IsTheSameFromBothSidesOfARefractedPair) {
  const double eta = 1.5;
  for (double theta_i = 0.0; theta_i < 1.5; theta_i += 0.1) {
    const double theta_t = std::asin(std::sin(theta_i) / eta);
    EXPECT_NEAR(FresnelDielectric(std::cos(theta_i), eta), FresnelDielectric(-std::cos(theta_t), eta), 1e-14);
  }
}

TEST(Fresnel, TotalInternalReflectionBeyondTheCriticalAngle) {
  const double eta = 1.5;
  const double critical = std::asin(1.0 / eta);
  EXPECT_LT(FresnelDielectric(-std::cos(critical - 0.01), eta), 1.0);
  EXPECT_EQ(FresnelDielectric(-std::cos(critical + 0.01), eta), 1.0);
}

TEST(Fresnel, ParallelPolarisationVanishesAtBrewstersAngle) {
  const double eta = 1.5;
  const double brewster = std::atan(eta);
  const double cos_i = std::cos(brewster);
  const double cos_t = std::sqrt(1 - (1 - cos_i * cos_i) / (eta * eta));
  const double r_perpendicular = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
  EXPECT_NEAR(FresnelDielectric(cos_i, eta), 0.5 * r_perpendicular * r_perpendicular, 1e-15);
  EXPECT_NEAR(FresnelDielectric(0.0, eta), 1.0, 1e-15);  // grazing incidence reflects everything
}

TEST(SmithShadowing, IsOneAtNormalIncidenceAndFallsTowardGrazing) {
  const SmithShadowing g = SmithShadowing::Ggx(0.3);
  const Vec3 h = Vec3::UnitZ();
  EXPECT_DOUBLE_EQ(g.G1(Vec3::UnitZ(), h), 1.0);
  double previous = 1.0;
  for (double theta = 0.1; theta < 1.5; theta += 0.1) {
    const double value = g.G1(SphericalDirection(theta, 0.3), h);
    EXPECT_LT(value, previous);
    EXPECT_GT(value, 0.0);
    previous = value;
  }
  // Side adjustment: a direction below the surface is treated as its mirror above it.
  EXPECT_DOUBLE_EQ(g.G1(FlipZ(SphericalDirection(0.7, 0.3)) * -1.0, h),
                   g.G1(SphericalDirection(0.7, 0.3) * 1.0, h));
  EXPECT_EQ(g.G1(SphericalDirection(1.2, 0.0), SphericalDirection(1.0, kPi)), 0.0);  // back-facing
  EXPECT_THROW(SmithShadowing::Ggx(-0.1), common::Error);
}

TEST(DualMicrofacet, RejectsAnIndexOfRefractionNotAboveOne) {
  EXPECT_THROW(DualMicrofacetModel(1.0), common::Error);
  EXPECT_THROW(DualMicrofacetModel(0.7), common::Error);
  EXPECT_THROW(DualMicrofacetModel(std::nan("")), common::Error);
}

TEST(DualMicrofacet, JacobianMatchesFiniteDifferences) {
  const double eta = 1.5;
  const DualMicrofacetModel model(eta);
  const auto ggx = Ggx(0.3, 0.3);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> uniform(0, 1);
  int checked = 0;
  for (int trial = 0; trial < 200 && checked < 60; ++trial) {
    const Vec3 i = LightDirection(75 * uniform(rng), 360 * uniform(rng));
    const Vec3 o = SphericalDirection(1.3 * uniform(rng), kTwoPi * uniform(rng));
    const VirtualConfiguration entry = model.RoughEntry(i, o);
    const VirtualConfiguration exit = model.RoughExit(i, o);
    if (!entry.valid || !exit.valid) continue;
    ++checked;
    // Closed forms (docs/model.md): rough entry |om.h| o.z / (om.z |i + om|^2) and rough exit
    // |o.h| / |im - o|^2, derived from Walter et al. 2007 eq. 17 and the flat interface's
    // solid-angle compression.
    const Vec3 om(o.x(), o.y(), std::sqrt(eta * eta - o.x() * o.x() - o.y() * o.y()));
    const Vec3 im(-i.x(), -i.y(), std::sqrt(eta * eta - i.x() * i.x() - i.y() * i.y()));
    const double closed_entry = std::abs(om.dot(entry.h)) * o.z() / (om.z() * (i + om).squaredNorm());
    const double closed_exit = std::abs(o.dot(exit.h)) / (im - o).squaredNorm();
    const double fd_entry = FiniteDifferenceJacobian([&](const Vec3& v) { return model.RoughEntry(i, v).h; }, o);
    const double fd_exit = FiniteDifferenceJacobian([&](const Vec3& v) { return model.RoughExit(i, v).h; }, o);
    EXPECT_NEAR(fd_entry / closed_entry, 1.0, 1e-3) << "i=" << i.transpose() << " o=" << o.transpose();
    EXPECT_NEAR(fd_exit / closed_exit, 1.0, 1e-3) << "i=" << i.transpose() << " o=" << o.transpose();
    // And the factors are exactly Fresnel x G x (|i.h| / |i.z|) x Jacobian / o.z.
    const double fresnel_entry = (1 - FresnelDielectric(-i.dot(entry.h), eta)) * (1 - FresnelDielectric(o.z(), eta));
    EXPECT_NEAR(entry.factor,
                fresnel_entry * std::abs(i.dot(entry.h)) / std::abs(i.z()) * closed_entry / o.z(),
                1e-12 * entry.factor);
    const double fresnel_exit = (1 - FresnelDielectric(-i.z(), eta)) * (1 - FresnelDielectric(o.dot(exit.h), eta));
    EXPECT_NEAR(exit.factor, fresnel_exit * std::abs(im.dot(exit.h)) / im.z() * closed_exit / o.z(),
                1e-12 * exit.factor);
  }
  EXPECT_GE(checked, 40);
}

TEST(DualMicrofacet, StraightThroughLimit) {
  // As the NDF narrows to a delta at z, all light goes from i to o = -i and the transmitted
  // energy tends to (1 - F_entry)(1 - F_exit) = (1 - F(|i.z|))^2.
  const double eta = 1.5;
  const DualMicrofacetModel model(eta);
  for (double theta_deg : {0.0, 30.0, 60.0}) {
    const Vec3 i = LightDirection(theta_deg, 20.0);
    const double expected = Square(1 - FresnelDielectric(-i.z(), eta));
    double previous_error = 1.0;
    for (double roughness : {0.02, 0.005, 0.00125}) {  // the error falls about linearly with roughness
      const auto ndf = Ggx(roughness, roughness);
      // The whole hemisphere, with the radial nodes concentrated around the straight-through
      // direction where the lobe is: GGX's heavy tails carry ~0.3% of the energy beyond 40 alpha.
      const double energy_T = IntegrateProjectedAround(
          [&](const Vec3& o) { return model.RhoT(*ndf, i, o); }, -i, kPi, 2000, 96);
      const double energy_B = IntegrateProjectedAround(
          [&](const Vec3& o) { return model.RhoB(*ndf, i, o); }, -i, kPi, 2000, 96);
      const double error = std::max(std::abs(energy_T - expected), std::abs(energy_B - expected));
      EXPECT_LT(error, previous_error * 1.01) << "theta " << theta_deg << " roughness " << roughness;
      previous_error = error;
    }
    EXPECT_LT(previous_error, 5e-4) << "theta " << theta_deg;
  }
}

TEST(DualMicrofacet, EnergyNeverExceedsOne) {
  // With Fresnel and a shadowing term consistent with the NDF (Smith roughness >= the NDF's),
  // the energy transmitted into the camera hemisphere is <= 1 for both configurations and, by
  // Hoelder's inequality, for every log-space blend. It is also well above zero for moderate
  // roughness (the paper's extracted eq. 26 Jacobian gives about 1.58 at 60 degrees).
  for (double eta : {1.1, 1.5, 2.0}) {
    for (double roughness : {0.05, 0.2, 0.6}) {
      const auto ndf = Ggx(roughness, 0.7 * roughness);
      const DualMicrofacetModel model(eta, SmithShadowing::Ggx(roughness));
      for (double theta_deg : {0.0, 45.0, 80.0}) {
        const Vec3 i = LightDirection(theta_deg, 30.0);
        for (double alpha : {0.0, 0.5, 1.0}) {
          const double energy = IntegrateProjectedAround(
              [&](const Vec3& o) { return model.Rho(*ndf, alpha, i, o); }, -i, kPi, 600, 192);
          EXPECT_LE(energy, 1.0) << "eta " << eta << " roughness " << roughness << " theta " << theta_deg
                                 << " alpha " << alpha;
          if (theta_deg < 50 && roughness < 0.5) {
            EXPECT_GT(energy, 0.5);
          }
        }
      }
    }
  }
}

TEST(DualMicrofacet, WithoutShadowingARoughNdfCanExceedOne) {
  // The reason the energy check needs a consistent G: without masking, a rough (alpha 0.6)
  // interface at eta 1.1 transmits more than it receives. Documented in docs/model.md.
  const auto ndf = Ggx(0.6, 0.42);
  const DualMicrofacetModel model(1.1);
  const Vec3 i = LightDirection(45.0, 30.0);
  const double energy =
      IntegrateProjectedAround([&](const Vec3& o) { return model.RhoT(*ndf, i, o); }, -i, kPi, 600, 192);
  EXPECT_GT(energy, 1.0);
}

TEST(DualMicrofacet, Reciprocity) {
  const double eta = 1.45;
  const auto skewed = SkewedNdf();
  const MirroredNdf mirrored(*skewed);
  for (const SmithShadowing shadowing : {SmithShadowing::None(), SmithShadowing::Ggx(0.3)}) {
    const DualMicrofacetModel model(eta, shadowing);
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> uniform(0, 1);
    int nonzero = 0;
    for (int trial = 0; trial < 500; ++trial) {
      const Vec3 i = LightDirection(85 * uniform(rng), 360 * uniform(rng));
      const Vec3 o = SphericalDirection(85 * uniform(rng) * kPi / 180, kTwoPi * uniform(rng));
      const double rho_T = model.RhoT(*skewed, i, o);
      const double rho_B_flipped = model.RhoB(mirrored, FlipZ(o), FlipZ(i));
      EXPECT_NEAR(rho_T, rho_B_flipped, 1e-12 * std::max(1.0, rho_T));
      nonzero += rho_T > 1e-6;
    }
    EXPECT_GT(nonzero, 100);  // the check is not vacuous
  }
}

TEST(DualMicrofacet, SkewMakesTheReciprocityCheckMeaningful) {
  // Guard for the test above: with the unmirrored NDF the identity must fail.
  const auto skewed = SkewedNdf();
  const DualMicrofacetModel model(1.45);
  const Vec3 i = LightDirection(30, 10);
  const Vec3 o = SphericalDirection(0.4, 2.0);
  EXPECT_GT(std::abs(model.RhoT(*skewed, i, o) - model.RhoB(*skewed, FlipZ(o), FlipZ(i))),
            1e-3 * model.RhoT(*skewed, i, o));
}

TEST(DualMicrofacet, RoughEntryIsWalterThroughAFlatExit) {
  // rho_T = (1 - F(o.z)) f_W(i -> t; 1, eta) / eta^2 and rho_B = (1 - F(|i.z|)) f_W(-t_i -> o; eta, 1)
  // when the shadowing is the NDF's own GGX Smith term.
  const double eta = 1.5, roughness = 0.25;
  const auto ndf = Ggx(roughness, roughness);
  const DualMicrofacetModel model(eta, SmithShadowing::Ggx(roughness));
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> uniform(0, 1);
  for (int trial = 0; trial < 300; ++trial) {
    const Vec3 i = LightDirection(80 * uniform(rng), 360 * uniform(rng));
    const Vec3 o = SphericalDirection(1.35 * uniform(rng), kTwoPi * uniform(rng));
    const Vec3 t = Vec3(o.x(), o.y(), std::sqrt(eta * eta - o.x() * o.x() - o.y() * o.y())) / eta;
    const Vec3 t_i = Vec3(-i.x(), -i.y(), std::sqrt(eta * eta - i.x() * i.x() - i.y() * i.y())) / eta;
    const double walter_T = (1 - FresnelDielectric(o.z(), eta)) * WalterBtdf(*ndf, i, t, 1.0, eta) / (eta * eta);
    const double walter_B = (1 - FresnelDielectric(-i.z(), eta)) * WalterBtdf(*ndf, -t_i, o, eta, 1.0);
    EXPECT_NEAR(model.RhoT(*ndf, i, o), walter_T, 1e-12 * std::max(1.0, walter_T));
    EXPECT_NEAR(model.RhoB(*ndf, i, o), walter_B, 1e-12 * std::max(1.0, walter_B));
  }
}

// HalfVectors (the renderer's cheap look at where a pair of directions falls in D) gives each
// configuration's h and validity exactly as RoughEntry and RoughExit do, over the whole sphere of
// light directions (so that invalid pairs, lit from above, are among them).
TEST(DualMicrofacet, HalfVectorsAreTheConfigurationsOwn) {
  const DualMicrofacetModel model(1.45, SmithShadowing::Ggx(0.3));
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> uniform(0, 1);
  int valid[2] = {0, 0}, invalid[2] = {0, 0};
  for (int trial = 0; trial < 2000; ++trial) {
    const Vec3 i = SphericalDirection(kPi * uniform(rng), kTwoPi * uniform(rng));
    const Vec3 o = SphericalDirection(1.5 * uniform(rng), kTwoPi * uniform(rng));
    const std::array<std::optional<Vec3>, 2> h = model.HalfVectors(i, o);
    const VirtualConfiguration configurations[2] = {model.RoughEntry(i, o), model.RoughExit(i, o)};
    for (int c = 0; c < 2; ++c) {
      ASSERT_EQ(h[c].has_value(), configurations[c].valid) << c;
      if (!h[c]) {
        ++invalid[c];
        continue;
      }
      ++valid[c];
      EXPECT_EQ(*h[c], configurations[c].h) << c;
    }
  }
  for (int c = 0; c < 2; ++c) {
    EXPECT_GT(valid[c], 300) << c;  // 461 and 492 of 2,000
    EXPECT_GT(invalid[c], 300) << c;
  }
}

TEST(DualMicrofacet, LogBlendInterpolatesInLogSpace) {
  EXPECT_DOUBLE_EQ(LogBlend(4.0, 1.0, 0.5), 2.0);
  EXPECT_DOUBLE_EQ(LogBlend(4.0, 0.0, 1.0), 4.0);  // the unused term may vanish at the ends
  EXPECT_DOUBLE_EQ(LogBlend(0.0, 3.0, 0.0), 3.0);
  EXPECT_DOUBLE_EQ(LogBlend(4.0, 0.0, 0.5), 0.0);
  const double rho = LogBlend(0.8, 0.2, 0.3);
  EXPECT_NEAR(std::log(rho), 0.3 * std::log(0.8) + 0.7 * std::log(0.2), 1e-15);
}

TEST(DualMicrofacet, MaterialAddsDiffuseToTheScaledRefractivePart) {
  const auto ndf = Ggx(0.2, 0.2);
  DualMicrofacetParams params;
  params.eta = 1.5;
  params.alpha = 0.4;
  params.k_s = {0.9, 0.5, 0.1};
  params.rho_d = {0.01, 0.02, 0.03};
  const Vec3 i = LightDirection(20, 0), o = SphericalDirection(0.3, kPi);
  const double rho = DualMicrofacetModel(params.eta).Rho(*ndf, params.alpha, i, o);
  ASSERT_GT(rho, 0.0);
  const Rgb value = EvaluateMaterial(*ndf, params, i, o);
  for (int c = 0; c < 3; ++c) EXPECT_DOUBLE_EQ(value[c], params.k_s[c] * rho + params.rho_d[c]);
}

}  // namespace
}  // namespace svbtdf::model
