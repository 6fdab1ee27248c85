#include "svbtdf/simulate/slab_tracer.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <numeric>
#include <optional>
#include <string>
#include <thread>

#include "svbtdf/common/error.h"
#include "svbtdf/common/interrupt.h"
#include "svbtdf/common/progress.h"
#include "svbtdf/model/fresnel.h"

namespace svbtdf::simulate {
namespace {

// The facet a path meets at one interface hit, oriented toward the side the path arrives from.
struct Facet {
  model::Vec3 h = model::Vec3::UnitZ();   // the NDF's normal, upper hemisphere (for D and G1)
  model::Vec3 n = model::Vec3::UnitZ();   // the same facet's normal on the arriving side: sign(v.z) h
  double weight = 1.0;      // the visible-normal sampler's weight (1 for exact samplers)
};

Facet SampleFacet(const SlabInterface& interface, const model::Vec3& v, common::Pcg32& rng) {
  Facet facet;
  const double side = v.z() > 0 ? 1.0 : -1.0;
  if (!interface.flat()) {
    // Seen from below, the microsurface shows the same facets with normals -h, and the normals
    // visible from v are those visible from the side-adjusted -v (Walter et al. 2007 eq. 23).
    const double u0 = rng.NextDouble();
    const double u1 = rng.NextDouble();
    const model::NormalSample sample = interface.ndf->SampleVisibleNormal(side * v, model::Vec2(u0, u1));
    facet.h = sample.h;
    facet.weight = sample.weight;
  }
  facet.n = side * facet.h;
  return facet;
}

// Refracts v (pointing away from the facet on the arriving side, v.n = cos_i > 0) through a
// facet with relative index eta_rel = n_transmitted / n_incident; Walter et al. 2007 eq. 40.
// The caller has excluded total internal reflection.
model::Vec3 Refract(const model::Vec3& v, const model::Vec3& n, double cos_i, double eta_rel) {
  const double inv_eta = 1.0 / eta_rel;
  const double sin2_t = inv_eta * inv_eta * std::max(0.0, 1.0 - cos_i * cos_i);
  const double cos_t = std::sqrt(std::max(0.0, 1.0 - sin2_t));
  return (inv_eta * cos_i - cos_t) * n - inv_eta * v;
}

void ValidateDirection(const model::Vec3& v, const char* subject, bool upper) {
  if (!v.allFinite() || std::abs(v.squaredNorm() - 1.0) > 1e-9) {
    common::ThrowInvalidInput(subject, "must be a finite unit vector");
  }
  if (upper ? !(v.z() > 0) : !(v.z() < 0)) {
    common::ThrowInvalidInput(subject, upper ? "must point toward the camera (z > 0)"
                                     : "must point toward the light (z < 0)",
                      "directions point away from the sample; z is the normal toward the camera");
  }
}

// Sums over one chunk of paths (or over all chunks reduced so far).
struct Tally {
  explicit Tally(int cells)
      : sum(cells, 0.0), sum_squares(cells, 0.0), energy(cells, 0.0), hits(cells, 0) {}

  void Add(const Tally& other) {
    for (size_t c = 0; c < sum.size(); ++c) {
      sum[c] += other.sum[c];
      sum_squares[c] += other.sum_squares[c];
      energy[c] += other.energy[c];
      hits[c] += other.hits[c];
    }
    for (int k = 0; k < 5; ++k) {
      fractions[k] += other.fractions[k];
      fraction_squares[k] += other.fraction_squares[k];
    }
    paths += other.paths;
  }

  std::vector<double> sum;          // per cell, of the per-path estimate of the cell mean of rho
  std::vector<double> sum_squares;  // of its square
  std::vector<double> energy;       // per cell, of the energy that left through it
  std::vector<int64_t> hits;        // per cell, paths that left through it
  std::array<double, 5> fractions{};  // transmitted, reflected, absorbed, masked, capped
  std::array<double, 5> fraction_squares{};
  int64_t paths = 0;
};

std::array<double, 5> AsArray(const EnergyFractions& e) {
  return {e.transmitted, e.reflected, e.absorbed, e.masked, e.capped};
}

EnergyFractions FromArray(const std::array<double, 5>& a) {
  return {a[0], a[1], a[2], a[3], a[4]};
}

// Standard error of the mean of n samples with the given sum and sum of squares.
double StandardError(double sum, double sum_squares, int64_t n) {
  if (n < 2) return std::numeric_limits<double>::infinity();
  const double mean = sum / n;
  const double variance = std::max(0.0, (sum_squares - sum * mean) / (n - 1));
  return std::sqrt(variance / n);
}

}  // namespace

double BtdfSlice::DominantRelativeError(double energy_fraction) const {
  const double total = std::accumulate(energy.begin(), energy.end(), 0.0);
  if (!(total > 0)) return std::numeric_limits<double>::infinity();
  std::vector<int> order(energy.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return energy[a] > energy[b]; });
  double accumulated = 0.0;
  double worst = 0.0;
  for (int cell : order) {
    if (accumulated >= energy_fraction * total) break;
    accumulated += energy[cell];
    worst = std::max(worst, rho[cell] > 0 ? standard_error[cell] / rho[cell]
                                          : std::numeric_limits<double>::infinity());
  }
  return worst;
}

SlabTracer::SlabTracer(Slab slab) : slab_(std::move(slab)) {
  if (!(slab_.eta > 1.0) || !std::isfinite(slab_.eta)) {
    common::ThrowInvalidInput("eta", "the slab's relative index must be finite and > 1, got " +
                                 std::to_string(slab_.eta),
                      "eta = n_slab / n_air, e.g. 1.5 for glass");
  }
  if (!(slab_.optical_depth >= 0.0) || !std::isfinite(slab_.optical_depth)) {
    common::ThrowInvalidInput("optical depth", "must be finite and >= 0, got " +
                                           std::to_string(slab_.optical_depth),
                      "0 means a clear slab");
  }
}

PathRecord SlabTracer::TracePath(const model::Vec3& direction, common::Pcg32& rng, int max_interactions) const {
  PathRecord record;
  const bool from_camera_side = direction.z() < 0;
  double throughput = 1.0;
  bool inside = false;
  model::Vec3 w = direction;  // current travel direction
  for (int hit = 0; hit < max_interactions; ++hit) {
    // Outside, only the first interface can be next; inside, the travel direction decides.
    const bool at_exit_interface = inside ? w.z() > 0 : from_camera_side;
    const SlabInterface& interface = at_exit_interface ? slab_.exit : slab_.entry;
    const model::Vec3 v = -w;  // toward where the path came from
    const Facet facet = SampleFacet(interface, v, rng);
    record.interactions = hit + 1;

    const double cos_i = v.dot(facet.n);
    const double eta_rel = inside ? 1.0 / slab_.eta : slab_.eta;  // n_transmitted / n_incident
    const double reflectance = cos_i > 0 ? model::FresnelDielectric(cos_i, eta_rel) : 1.0;
    const bool reflect = rng.NextDouble() < reflectance;
    const model::Vec3 out = reflect ? model::Vec3(2.0 * cos_i * facet.n - v)
                             : Refract(v, facet.n, cos_i, eta_rel);
    // A reflection must stay on the arriving side of the macro surface, a refraction must cross
    // it; otherwise the outgoing ray meets the microsurface again, which single-scattering
    // microfacet theory counts as masked (G1 = 0).
    const bool stays_on_side = out.z() * v.z() > 0;
    const bool consistent = cos_i > 0 && (reflect ? stays_on_side : !stays_on_side && out.z() != 0);
    const double masking = !consistent ? 0.0 : interface.flat() ? 1.0 : interface.ndf->G1(out, facet.h);
    const double keep = facet.weight * masking;
    record.energy.masked += throughput * (1.0 - keep);
    throughput *= keep;
    if (throughput <= 0.0) return record;

    const bool leaves = inside != reflect;  // outside: refraction enters; inside: it leaves
    if (leaves) {
      record.left_slab = true;
      record.direction = out.normalized();
      record.transmitted = (out.z() < 0) == from_camera_side;
      (record.transmitted ? record.energy.transmitted : record.energy.reflected) = throughput;
      return record;
    }
    inside = true;
    w = out;
    if (slab_.optical_depth > 0) {
      const double attenuation = std::exp(-slab_.optical_depth / std::abs(w.z()));
      record.energy.absorbed += throughput * (1.0 - attenuation);
      throughput *= attenuation;
    }
  }
  record.energy.capped = throughput;
  return record;
}

BtdfSlice SlabTracer::SliceForView(const model::Vec3& o, const model::Hemicube& grid,
                                   const SliceOptions& options) const {
  ValidateDirection(o, "view direction o", /*upper=*/true);
  return TraceSlice(-o, grid, options);
}

BtdfSlice SlabTracer::SliceForLight(const model::Vec3& i, const model::Hemicube& grid,
                                    const SliceOptions& options) const {
  ValidateDirection(i, "light direction i", /*upper=*/false);
  return TraceSlice(-i, grid, options);
}

BtdfSlice SlabTracer::TraceSlice(const model::Vec3& arrival, const model::Hemicube& grid,
                                 const SliceOptions& options) const {
  if (options.paths < 2) common::ThrowInvalidInput("paths", "need at least 2 paths for an error estimate");
  if (options.max_interactions < 1) common::ThrowInvalidInput("max interactions", "must be >= 1");
  const auto start = std::chrono::steady_clock::now();
  const int cells = grid.num_cells();
  std::vector<double> inverse_solid_angle(cells);
  for (int c = 0; c < cells; ++c) inverse_solid_angle[c] = 1.0 / grid.CellSolidAngle(c);
  // Transmitted paths leave on the far side; the grid covers the upper hemisphere.
  const bool exit_below = arrival.z() < 0;

  const auto trace_chunk = [&](int64_t chunk, int64_t count) {
    Tally tally(cells);
    common::Pcg32 rng(options.seed, static_cast<uint64_t>(chunk));
    for (int64_t p = 0; p < count; ++p) {
      const PathRecord path = TracePath(arrival, rng, options.max_interactions);
      const std::array<double, 5> e = AsArray(path.energy);
      for (int k = 0; k < 5; ++k) {
        tally.fractions[k] += e[k];
        tally.fraction_squares[k] += e[k] * e[k];
      }
      if (path.transmitted && path.energy.transmitted > 0) {
        const model::Vec3 upper = exit_below ? model::FlipZ(path.direction) : path.direction;
        const int cell = grid.CellOf(upper);
        // The cell mean of rho is (1 / Omega_c) integral_c p(d) / |d.z| d omega, estimated per path
        // by throughput / (|d.z| Omega_c) if the path lands in c, else 0.
        const double estimate = path.energy.transmitted * inverse_solid_angle[cell] / upper.z();
        tally.sum[cell] += estimate;
        tally.sum_squares[cell] += estimate * estimate;
        tally.energy[cell] += path.energy.transmitted;
        ++tally.hits[cell];
      }
    }
    tally.paths = count;
    return tally;
  };

  const int threads = options.threads > 0
                          ? options.threads
                          : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  std::optional<common::ProgressBar> progress;
  if (options.show_progress) progress.emplace("tracing", options.paths, "paths");

  Tally total(cells);
  BtdfSlice slice;
  const auto finish_slice = [&] {
    slice.rho.resize(cells);
    slice.standard_error.resize(cells);
    slice.energy.resize(cells);
    slice.hits = total.hits;
    const int64_t n = total.paths;
    for (int c = 0; c < cells; ++c) {
      slice.rho[c] = total.sum[c] / n;
      slice.standard_error[c] = StandardError(total.sum[c], total.sum_squares[c], n);
      slice.energy[c] = total.energy[c] / n;
    }
    std::array<double, 5> mean{}, error{};
    for (int k = 0; k < 5; ++k) {
      mean[k] = total.fractions[k] / n;
      error[k] = StandardError(total.fractions[k], total.fraction_squares[k], n);
    }
    slice.fractions = FromArray(mean);
    slice.fractions_standard_error = FromArray(error);
    slice.paths = n;
  };

  const int64_t total_chunks = (options.paths + kChunkPaths - 1) / kChunkPaths;
  const int64_t batch_chunks =
      options.target_relative_error > 0 ? kBatchPaths / kChunkPaths : total_chunks;
  for (int64_t batch_begin = 0; batch_begin < total_chunks; batch_begin += batch_chunks) {
    const int64_t batch_end = std::min(total_chunks, batch_begin + batch_chunks);
    // Chunks finish in any order but are added in chunk order, so that the floating-point sums,
    // and with them the result, do not depend on the number of threads.
    std::atomic<int64_t> next_chunk{batch_begin};
    std::mutex reduce_mutex;
    std::map<int64_t, Tally> finished;
    int64_t next_to_reduce = batch_begin;
    const auto worker = [&] {
      for (;;) {
        if (common::InterruptRequested()) return;
        const int64_t chunk = next_chunk.fetch_add(1);
        if (chunk >= batch_end) return;
        const int64_t count = std::min(kChunkPaths, options.paths - chunk * kChunkPaths);
        Tally tally = trace_chunk(chunk, count);
        const std::lock_guard<std::mutex> lock(reduce_mutex);
        finished.emplace(chunk, std::move(tally));
        for (auto it = finished.find(next_to_reduce); it != finished.end();
             it = finished.find(next_to_reduce)) {
          total.Add(it->second);
          finished.erase(it);
          ++next_to_reduce;
        }
        if (progress) progress->Advance(count);
      }
    };
    std::vector<std::thread> pool;
    for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
    worker();
    for (std::thread& thread : pool) thread.join();
    common::ThrowIfInterrupted("Monte Carlo slab tracing");

    finish_slice();
    if (options.target_relative_error > 0 &&
        slice.DominantRelativeError(options.dominant_energy_fraction) <=
            options.target_relative_error) {
      break;
    }
  }
  if (progress) progress->Finish();
  slice.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return slice;
}

}  // namespace svbtdf::simulate
