#pragma once
// An NDF tabulated on a hemicube as ln D per cell (docs/hemicube.md): what the fit recovers.
// D(h) = exp(bilinear interpolation of ln D), so that the fitting system stays linear in ln D.

#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "svbtdf/model/hemicube.h"
#include "svbtdf/model/ndf.h"

namespace svbtdf::model {

class TabulatedNdf final : public Ndf {
 public:
  // Throws svbtdf::Error(kInvalidInput) when ln_d has the wrong length or non-finite values.
  TabulatedNdf(const Hemicube& grid, std::vector<double> ln_d);
  // Samples `ndf` at the cell centres (D = 0 becomes ln D = -700).
  TabulatedNdf(const Hemicube& grid, const Ndf& ndf);
  TabulatedNdf(const TabulatedNdf& other);

  const Hemicube& grid() const { return grid_; }
  const std::vector<double>& ln_d() const { return ln_d_; }

  // Scales D so that the integral of D(h) h.z over the hemisphere is 1 under this class's own
  // evaluation rule (4x4 sub-cell quadrature); returns the integral before scaling.
  double Normalize();
  // The integral of D(h) h.z by that quadrature.
  double ProjectedIntegral() const;

  std::string name() const override { return "tabulated"; }
  double D(const Vec3& h) const override;
  // Smith masking from the table's own projected area: G1 = chi+ min(1, v.z / A(v)),
  // A(v) = integral of max(0, v.h) D(h), tabulated over the direction of v on first use.
  double G1(const Vec3& v, const Vec3& h) const override;
  // Exact sampling of max(0, v.h) D(h) by rejection from a per-cell bound; the reported pdf is
  // max(0, v.h) D(h) / A(v) with the tabulated A, so the weight is min(1, A(v) / v.z) <= 1.
  NormalSample SampleVisibleNormal(const Vec3& v, const Vec2& u) const override;
  double VisibleNormalPdf(const Vec3& v, const Vec3& h) const override;
  std::unique_ptr<Ndf> Clone() const override { return std::make_unique<TabulatedNdf>(*this); }

  // The projected area A(v) of the microsurface seen from v (v.z > 0), from the table.
  double ProjectedArea(const Vec3& v) const;

 private:
  struct AreaTable;
  const AreaTable& Areas() const;

  Hemicube grid_;
  std::vector<double> ln_d_;
  mutable std::mutex areas_mutex_;
  mutable std::shared_ptr<const AreaTable> areas_;  // built on first use
};

}  // namespace svbtdf::model
