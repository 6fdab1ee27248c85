#pragma once
// An NDF tabulated on a hemicube as ln D per cell (docs/hemicube.md): what the fit recovers.
// D(h) = exp(bilinear interpolation of ln D), so that the fitting system stays linear in ln D.

#include <atomic>
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
  // Exact sampling of max(0, v.h) D(h) by rejection from a per-cell bound that does not depend
  // on v (built once); the reported pdf is max(0, v.h) D(h) / A(v) with the tabulated A, so the
  // weight is min(1, A(v) / v.z) <= 1. Views within about a degree of the horizon are slow.
  NormalSample SampleVisibleNormal(const Vec3& v, const Vec2& u) const override;
  double VisibleNormalPdf(const Vec3& v, const Vec3& h) const override;
  std::unique_ptr<Ndf> Clone() const override { return std::make_unique<TabulatedNdf>(*this); }

  // The projected area A(v) of the microsurface seen from v (v.z > 0), from the table.
  double ProjectedArea(const Vec3& v) const;

 private:
  struct AreaTable;
  struct SamplingTable;

  // A table derived from ln_d_, built once by the first caller that needs it. Later calls read
  // it through the atomic pointer without taking the lock: renderers call D, G1 and the sampler
  // from every thread at once.
  template <typename Table>
  struct LazyTable {
    std::mutex mutex;
    std::shared_ptr<const Table> table;
    std::atomic<const Table*> ready{nullptr};

    template <typename Build>
    const Table& Get(const Build& build) {
      if (const Table* built = ready.load(std::memory_order_acquire)) return *built;
      std::lock_guard<std::mutex> lock(mutex);
      if (!table) {
        table = build();
        ready.store(table.get(), std::memory_order_release);
      }
      return *table;
    }
    void Reset() {
      std::lock_guard<std::mutex> lock(mutex);
      ready.store(nullptr, std::memory_order_release);
      table.reset();
    }
  };

  const AreaTable& Areas() const;
  const SamplingTable& Sampling() const;

  Hemicube grid_;
  std::vector<double> ln_d_;
  mutable LazyTable<AreaTable> areas_;
  mutable LazyTable<SamplingTable> sampling_;
};

}  // namespace svbtdf::model
