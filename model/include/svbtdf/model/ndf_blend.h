#pragma once
// A weighted sum of tabulated NDFs on one hemicube, D(h) = sum_j c_j D_j(h): the NDF of a fitted
// material's texel as a renderer evaluates it, without building the texel's own table (which
// costs about a millisecond: a blend costs one interpolation and one exp per component).
//
// The weights are affine (they may be negative). D is clamped at 0 where negative weights make
// the sum undershoot. Visible normals are drawn from the mixture of the components with positive
// weight, component j with probability c_j A_j(v) / sum_k c_k A_k(v), and reported with that
// mixture's exact density: for non-negative weights it is exactly the blend's visible-normal
// distribution; otherwise it is a proposal, and the weight of the sample says so.

#include <array>

#include "svbtdf/model/ndf.h"
#include "svbtdf/model/tabulated_ndf.h"

namespace svbtdf::model {

class TabulatedNdfBlend final : public Ndf {
 public:
  static constexpr int kMaxComponents = 16;

  TabulatedNdfBlend() = default;
  // Throws svbtdf::Error(kInvalidInput) beyond kMaxComponents, for a component on another
  // hemicube than the first's, or for a non-finite weight. Zero weights are skipped.
  void Add(const TabulatedNdf& ndf, double weight);
  int size() const { return count_; }

  std::string name() const override { return "tabulated-blend"; }
  double D(const Vec3& h) const override;
  // chi+ min(1, v.z / A(v)) with A(v) = sum of the positive components' c_j A_j(v).
  double G1(const Vec3& v, const Vec3& h) const override;
  NormalSample SampleVisibleNormal(const Vec3& v, const Vec2& u) const override;
  double VisibleNormalPdf(const Vec3& v, const Vec3& h) const override;
  std::unique_ptr<Ndf> Clone() const override { return std::make_unique<TabulatedNdfBlend>(*this); }

 private:
  struct Component {
    const TabulatedNdf* ndf = nullptr;
    double weight = 0.0;
  };
  // The positive components' c_j A_j(v) into `mass`; returns their sum.
  double SamplingMasses(const Vec3& v, std::array<double, kMaxComponents>& mass) const;

  std::array<Component, kMaxComponents> components_{};
  int count_ = 0;
};

}  // namespace svbtdf::model
