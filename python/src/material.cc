// svbtdf.Material: a fitted material's maps as arrays, its BTDF evaluated as `svbtdf eval` does
// (fit::MaterialEvaluator), vectorised over texels and direction pairs on the project's parallel
// loop with the GIL released, and the renderer-ready BSDF (render::MaterialSurface) for sampling.

#include <algorithm>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "bindings.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/parallel.h"
#include "svbtdf/fit/material.h"
#include "svbtdf/model/hemicube.h"
#include "svbtdf/render/surface.h"

namespace svbtdf::python {
namespace {

// Loops over N items of at least this many per chunk, so that small calls stay on one thread.
constexpr int64_t kChunk = 4096;

// work() with the GIL released (other Python threads run meanwhile), taken back before anything
// touches a Python object again.
template <typename Work>
auto WithoutGil(const Work& work) {
  py::gil_scoped_release release;
  return work();
}

class Material {
 public:
  // The evaluator and the surface refer to material_: a Material never moves (pybind11 holds it
  // by unique_ptr).
  explicit Material(const std::filesystem::path& folder)
      : folder_(folder),
        material_(fit::ReadMaterial(folder)),
        evaluator_(material_),
        surface_(material_, material_.width_m > 0 ? material_.width_m : 1.0,
                 material_.height_m > 0 ? material_.height_m : 1.0, folder.string()),
        texels_(static_cast<size_t>(material_.width) * material_.height) {}
  Material(const Material&) = delete;
  Material& operator=(const Material&) = delete;

  const fit::Material& material() const { return material_; }
  const std::filesystem::path& folder() const { return folder_; }

  // The texel index (row * width + col) of texel i of an (N, 2) array of (col, row), or of a
  // (2,) array for every i; svbtdf::Error naming the texel when it lies outside the material.
  int64_t TexelIndex(const IntArray& texels, int64_t i) const {
    const int64_t* p = texels.data() + (texels.ndim() == 1 ? 0 : 2 * i);
    CheckTexel(p[0], p[1]);
    return p[1] * material_.width + p[0];
  }

  // N of an (N, 2) or (2,) texel array checked against the directions' count.
  static int64_t Count(const IntArray& texels, std::initializer_list<int64_t> others) {
    int64_t n = 1;
    if (texels.ndim() == 2 && texels.shape(1) == 2) {
      n = texels.shape(0);
    } else if (!(texels.ndim() == 1 && texels.shape(0) == 2)) {
      common::ThrowInvalidInput("texels", "must be an array of shape (N, 2) of (column, row), or (2,)");
    }
    for (const int64_t other : others) {
      if (n == 1) n = other;
      else if (other != 1 && other != n) common::ThrowInvalidInput("texels", "and the directions have different lengths");
    }
    return n;
  }

  // R(x, i, o) as `svbtdf eval` computes it: (N, 3). The directions are read, checked and
  // normalised inside the parallel loop: done up front, on one thread, they took as long as the
  // evaluations.
  py::array_t<double> Eval(const IntArray& texels, const DoubleArray& wi, const DoubleArray& wo, int threads) {
    const int64_t n = Count(texels, {DirectionCount(wi, "wi"), DirectionCount(wo, "wo")});
    py::array_t<double> out({n, int64_t{3}});
    double* values = out.mutable_data();
    const std::vector<int64_t> index = Indices(texels, n);
    const int64_t refused = WithoutGil([&] {
      std::lock_guard<std::mutex> lock(texels_mutex_);
      BuildTexels(index, threads);
      return ParallelOverPairs(n, threads, [&] {
        return [&](int64_t k) {
          const std::optional<model::Vec3> i = UnitOnSide(Direction(wi, k), kBelow), o = UnitOnSide(Direction(wo, k), kAbove);
          if (!i || !o) return false;
          const model::Rgb r = (*texels_[index[k]])->Evaluate(*i, *o);
          std::copy(r.begin(), r.end(), values + 3 * k);
          return true;
        };
      });
    });
    if (refused >= 0) RefusePair(wi, wo, refused, kBelow, kAbove);
    return out;
  }

  // The renderer's BSDF (render::MaterialSurface) at each texel: f(wi, wo) per channel.
  py::array_t<double> BsdfEval(const IntArray& texels, const DoubleArray& wi, const DoubleArray& wo, int threads) const {
    const int64_t n = Count(texels, {DirectionCount(wi, "wi"), DirectionCount(wo, "wo")});
    py::array_t<double> out({n, int64_t{3}});
    double* values = out.mutable_data();
    const std::vector<int64_t> index = Indices(texels, n);
    const int64_t refused = WithoutGil([&] {
      return ForEachBsdf(index, threads, [&](int64_t k, const model::Bsdf& bsdf) {
        const std::optional<model::Vec3> i = UnitOnSide(Direction(wi, k), kEither), o = UnitOnSide(Direction(wo, k), kEither);
        if (!i || !o) return false;
        const model::Rgb f = bsdf.Eval(*i, *o);
        std::copy(f.begin(), f.end(), values + 3 * k);
        return true;
      });
    });
    if (refused >= 0) RefusePair(wi, wo, refused, kEither, kEither);
    return out;
  }

  // Bsdf::Pdf: the density with which Sample(wo) returns wi, (N,).
  py::array_t<double> Pdf(const IntArray& texels, const DoubleArray& wi, const DoubleArray& wo, int threads) const {
    const int64_t n = Count(texels, {DirectionCount(wi, "wi"), DirectionCount(wo, "wo")});
    py::array_t<double> out(n);
    double* values = out.mutable_data();
    const std::vector<int64_t> index = Indices(texels, n);
    const int64_t refused = WithoutGil([&] {
      return ForEachBsdf(index, threads, [&](int64_t k, const model::Bsdf& bsdf) {
        const std::optional<model::Vec3> i = UnitOnSide(Direction(wi, k), kEither), o = UnitOnSide(Direction(wo, k), kEither);
        if (!i || !o) return false;
        values[k] = bsdf.Pdf(*i, *o);
        return true;
      });
    });
    if (refused >= 0) RefusePair(wi, wo, refused, kEither, kEither);
    return out;
  }

  // Bsdf::Sample with u = (u_lobe, u_x, u_y) per row: (wi, pdf, weight, valid).
  py::tuple Sample(const IntArray& texels, const DoubleArray& wo, const DoubleArray& u, int threads) const {
    const int64_t n = Count(texels, {DirectionCount(wo, "wo"), DirectionCount(u, "u")});
    const std::vector<int64_t> index = Indices(texels, n);
    py::array_t<double> wi({n, int64_t{3}}), pdf(n), weight({n, int64_t{3}});
    py::array_t<bool> valid(n);
    double *wi_out = wi.mutable_data(), *pdf_out = pdf.mutable_data(), *weight_out = weight.mutable_data();
    bool* valid_out = valid.mutable_data();
    const int64_t refused = WithoutGil([&] {
      return ForEachBsdf(index, threads, [&](int64_t k, const model::Bsdf& bsdf) {
        const std::optional<model::Vec3> o = UnitOnSide(Direction(wo, k), kEither);
        const model::Vec3 r = Direction(u, k);
        if (!o || !(r.minCoeff() >= 0 && r.maxCoeff() < 1)) return false;
        const std::optional<model::BsdfSample> s = bsdf.Sample(*o, r.x(), model::Vec2(r.y(), r.z()));
        valid_out[k] = s.has_value();
        for (int c = 0; c < 3; ++c) {
          wi_out[3 * k + c] = s ? s->wi[c] : 0.0;
          weight_out[3 * k + c] = s ? s->weight[c] : 0.0;
        }
        pdf_out[k] = s ? s->pdf : 0.0;
        return true;
      });
    });
    if (refused >= 0) {
      RefuseDirection(wo, refused, "wo", kEither);
      common::ThrowInvalidInput("u[" + std::to_string(refused) + "]", "must lie in [0, 1)");
    }
    return py::make_tuple(wi, pdf, weight, valid);
  }

  // The texel's NDF table (fit::MaterialEvaluator::TexelNdf) as D per hemicube cell.
  py::array_t<double> NdfCells(int col, int row) const {
    CheckTexel(col, row);
    const model::TabulatedNdf ndf = evaluator_.TexelNdf(col, row);
    py::array_t<double> out(static_cast<py::ssize_t>(ndf.ln_d().size()));
    std::transform(ndf.ln_d().begin(), ndf.ln_d().end(), out.mutable_data(), [](double l) { return std::exp(l); });
    return out;
  }

  // The same NDF at arbitrary unit normals h (N, 3): D(h), 0 below the horizon.
  py::array_t<double> NdfAt(int col, int row, const DoubleArray& h) const {
    const int64_t n = DirectionCount(h, "h");
    CheckTexel(col, row);
    const model::TabulatedNdf ndf = evaluator_.TexelNdf(col, row);
    py::array_t<double> out(n);
    for (int64_t k = 0; k < n; ++k) {
      const model::Vec3 v = Direction(h, k);
      out.mutable_data()[k] = v.norm() > 0 && std::isfinite(v.norm()) ? ndf.D(v.normalized()) : 0.0;
    }
    return out;
  }

 private:
  // Throws naming the texel when (col, row) lies outside the material.
  void CheckTexel(int64_t col, int64_t row) const {
    if (col < 0 || row < 0 || col >= material_.width || row >= material_.height) {
      common::ThrowInvalidInput("texel", "(" + std::to_string(col) + ", " + std::to_string(row) + ") is outside the " +
                                             std::to_string(material_.width) + "x" + std::to_string(material_.height) +
                                             " material");
    }
  }

  std::vector<int64_t> Indices(const IntArray& texels, int64_t n) const {
    std::vector<int64_t> index(n);
    for (int64_t k = 0; k < n; ++k) index[k] = TexelIndex(texels, k);
    return index;
  }

  // Which side of the sample a direction must point to: the light's (z < 0) and the camera's
  // (z > 0) for `svbtdf eval`; either, off the plane, for the renderer's BSDF.
  enum Side { kBelow, kAbove, kEither };

  // The unit direction of v, or nothing when v is zero, not finite or on the wrong side.
  static std::optional<model::Vec3> UnitOnSide(const model::Vec3& v, Side side) {
    const double norm = v.norm();
    if (!(norm > 0 && std::isfinite(norm))) return std::nullopt;
    if (side == kBelow ? !(v.z() < 0) : side == kAbove ? !(v.z() > 0) : v.z() == 0) return std::nullopt;
    return v / norm;
  }

  // Throws the error UnitOnSide's refusal of direction k of `a` stands for, as `svbtdf eval`
  // words it for --wi and --wo; returns when that direction is fine.
  static void RefuseDirection(const DoubleArray& a, int64_t k, const char* name, Side side) {
    const model::Vec3 v = Direction(a, k);
    if (UnitOnSide(v, side)) return;
    const std::string subject = std::string(name) + "[" + std::to_string(k) + "]";
    if (!v.allFinite() || v.norm() == 0.0) common::ThrowInvalidInput(subject, "must be a non-zero finite vector X Y Z");
    if (side == kBelow) common::ThrowInvalidInput(subject, "must point toward the light, below the sample (z < 0)");
    if (side == kAbove) common::ThrowInvalidInput(subject, "must point toward the camera, above the sample (z > 0)");
    common::ThrowInvalidInput(subject, "must not lie in the sample's plane (z = 0)");
  }

  static void RefusePair(const DoubleArray& wi, const DoubleArray& wo, int64_t k, Side wi_side, Side wo_side) {
    RefuseDirection(wi, k, "wi", wi_side);
    RefuseDirection(wo, k, "wo", wo_side);
  }

  // Runs each(k) over [0, n) on the parallel loop, with each = make_each() made once per chunk
  // (for state a chunk reuses). each returns false for an input it refuses (and leaves its output
  // alone). Returns the smallest refused k, or -1, so that the error names the first bad row
  // whatever the threads did.
  template <typename MakeEach>
  static int64_t ParallelOverPairs(int64_t n, int threads, const MakeEach& make_each) {
    std::atomic<int64_t> first_refused{n};
    common::ParallelFor(n, threads, kChunk, [&](int64_t begin, int64_t end) {
      auto each = make_each();
      for (int64_t k = begin; k < end; ++k) {
        if (each(k)) continue;
        int64_t seen = first_refused.load();
        while (k < seen && !first_refused.compare_exchange_weak(seen, k)) {
        }
        break;  // later rows of this chunk cannot be smaller
      }
    });
    return first_refused < n ? first_refused.load() : -1;
  }

  // Builds the TexelBtdf of every texel in `index` not built yet, in parallel; texels_mutex_ held.
  void BuildTexels(const std::vector<int64_t>& index, int threads) {
    std::vector<int64_t> missing;
    for (const int64_t t : index) {
      if (!texels_[t]) {
        missing.push_back(t);
        texels_[t] = std::make_unique<std::optional<fit::TexelBtdf>>();  // claims the slot: listed once
      }
    }
    try {
      common::ParallelFor(static_cast<int64_t>(missing.size()), threads, 1, [&](int64_t begin, int64_t end) {
        for (int64_t k = begin; k < end; ++k) {
          const int64_t t = missing[k];
          texels_[t]->emplace(evaluator_.Texel(static_cast<int>(t % material_.width), static_cast<int>(t / material_.width)));
        }
      });
    } catch (...) {
      for (const int64_t t : missing) texels_[t].reset();  // unclaimed again: a later call builds them
      throw;
    }
  }

  // ParallelOverPairs with texel k's BSDF from the renderer's surface, built in a scratch that
  // each chunk reuses from pair to pair (a scratch belongs to one surface: never keep it longer).
  template <typename Body>
  int64_t ForEachBsdf(const std::vector<int64_t>& index, int threads, const Body& body) const {
    return ParallelOverPairs(static_cast<int64_t>(index.size()), threads, [&] {
      return [&, scratch = std::make_shared<render::BsdfScratch>()](int64_t k) {
        const int64_t t = index[k];
        return body(k, surface_.At(static_cast<int>(t % material_.width), static_cast<int>(t / material_.width), *scratch));
      };
    });
  }

  std::filesystem::path folder_;
  fit::Material material_;
  fit::MaterialEvaluator evaluator_;
  render::MaterialSurface surface_;
  // Each texel's BTDF once built (its normalised NDF table is the expensive part), by texel index.
  std::vector<std::unique_ptr<std::optional<fit::TexelBtdf>>> texels_;
  std::mutex texels_mutex_;
};

py::object MapOrNone(const common::FloatImage& image) {
  if (image.pixels.empty()) return py::none();
  return ToArray(image);
}

// The hemicube's cell centres (C, 3) and solid angles (C,), the NDF tables' grid (docs/hemicube.md).
py::tuple HemicubeCells(int resolution) {
  const model::Hemicube grid(resolution);
  py::array_t<double> directions({grid.num_cells(), 3}), solid_angles(grid.num_cells());
  for (int c = 0; c < grid.num_cells(); ++c) {
    const model::Vec3 d = grid.CellCenter(c);
    for (int k = 0; k < 3; ++k) directions.mutable_data()[3 * c + k] = d[k];
    solid_angles.mutable_data()[c] = grid.CellSolidAngle(c);
  }
  return py::make_tuple(directions, solid_angles);
}

}  // namespace

void BindMaterial(py::module_& m) {
  m.def("hemicube_cells", &HemicubeCells, py::arg("resolution"),
        "The hemicube's cell centre directions, float64 (C, 3), and solid angles, float64 (C,), for a "
        "resolution N (C = N^2 + 2 N^2; docs/hemicube.md): the grid of Material.ndf_cells.");

  py::class_<Material>(m, "Material",
                       "A fitted material (docs/material-format.md). Load with Material.load(path). Maps are "
                       "float32 arrays indexed [row, column] (texel index row * width + column); a texel is "
                       "(column, row), as `svbtdf eval --texel U V`.")
      .def_static("load", [](const std::string& path) { return std::make_unique<Material>(path); }, py::arg("path"),
                  "Reads and checks MATERIAL/ (material.json and its maps). Raises svbtdf.FormatError, "
                  "svbtdf.IoError naming the file.")
      .def_property_readonly("path", [](const Material& m) { return m.folder().string(); })
      .def_property_readonly("width", [](const Material& m) { return m.material().width; }, "texels across")
      .def_property_readonly("height", [](const Material& m) { return m.material().height; }, "texels down")
      .def_property_readonly("eta", [](const Material& m) { return m.material().eta; })
      .def_property_readonly("btdf", [](const Material& m) { return std::string(fit::MaterialModelName(m.material().model)); },
                             "'dual-microfacet', 'walter-ggx' (the baseline) or 'slab' (two rough interfaces)")
      .def_property_readonly("ndf_resolution", [](const Material& m) { return m.material().ndf_resolution; })
      .def_property_readonly("sample_size", [](const Material& m) { return py::make_tuple(m.material().width_m, m.material().height_m); },
                             "(width, height) of the sample in metres; (0, 0) when not recorded")
      .def_property_readonly("representative_texels", [](const Material& m) {
            py::array_t<int64_t> out(static_cast<py::ssize_t>(m.material().representative_texels.size()));
            std::copy(m.material().representative_texels.begin(), m.material().representative_texels.end(), out.mutable_data());
            return out;
          }, "int64 (R,): texel index (row * width + column) of each representative")
      .def_property_readonly("provenance", [](const Material& m) { return ToPython(m.material().provenance); })
      .def_property_readonly("alpha", [](const Material& m) { return ToArray(m.material().alpha); }, "float32 (H, W): blend weight alpha")
      .def_property_readonly("shadowing_roughness", [](const Material& m) { return ToArray(m.material().shadowing_roughness); },
                             "float32 (H, W): Smith GGX roughness of the shadowing (0: none)")
      .def_property_readonly("k_s", [](const Material& m) { return ToArray(m.material().k_s); }, "float32 (H, W, 3)")
      .def_property_readonly("rho_d", [](const Material& m) { return ToArray(m.material().rho_d); }, "float32 (H, W, 3)")
      .def_property_readonly("residual", [](const Material& m) { return ToArray(m.material().residual); },
                             "float32 (H, W): relative RMSE of the texel's own samples (-1: not fitted)")
      .def_property_readonly("cluster", [](const Material& m) { return ToArray(m.material().cluster); },
                             "float32 (H, W): the representative of the texel's cluster")
      .def_property_readonly("weight_index", [](const Material& m) { return ToArray(m.material().weight_index, false); },
                             "float32 (H, W, K): representatives of the texel's affine blend")
      .def_property_readonly("weight_value", [](const Material& m) { return ToArray(m.material().weight_value, false); },
                             "float32 (H, W, K): their weights (sum 1; unused: 0)")
      .def_property_readonly("baseline_alpha_x", [](const Material& m) { return MapOrNone(m.material().baseline_alpha_x); },
                             "float32 (H, W) for a walter-ggx material, else None")
      .def_property_readonly("baseline_alpha_y", [](const Material& m) { return MapOrNone(m.material().baseline_alpha_y); },
                             "float32 (H, W) for a walter-ggx material, else None")
      .def_property_readonly("baseline_azimuth", [](const Material& m) { return MapOrNone(m.material().baseline_azimuth); },
                             "float32 (H, W) for a walter-ggx material, else None")
      .def_property_readonly("slab_entry_alpha_x", [](const Material& m) { return MapOrNone(m.material().slab_entry_alpha_x); },
                             "float32 (H, W): GGX alpha along the first axis of the side facing the light, for a slab "
                             "material, else None")
      .def_property_readonly("slab_entry_alpha_y", [](const Material& m) { return MapOrNone(m.material().slab_entry_alpha_y); },
                             "float32 (H, W): across it, for a slab material, else None")
      .def_property_readonly("slab_entry_azimuth", [](const Material& m) { return MapOrNone(m.material().slab_entry_azimuth); },
                             "float32 (H, W): the first axis's angle from +x, radians, for a slab material, else None")
      .def_property_readonly("slab_exit_alpha_x", [](const Material& m) { return MapOrNone(m.material().slab_exit_alpha_x); },
                             "float32 (H, W): the same for the side facing the camera, for a slab material, else None")
      .def_property_readonly("slab_exit_alpha_y", [](const Material& m) { return MapOrNone(m.material().slab_exit_alpha_y); },
                             "float32 (H, W): for a slab material, else None")
      .def_property_readonly("slab_exit_azimuth", [](const Material& m) { return MapOrNone(m.material().slab_exit_azimuth); },
                             "float32 (H, W): for a slab material, else None")
      .def_property_readonly("slab_entry_roughness_se",
                             [](const Material& m) { return MapOrNone(m.material().slab_entry_roughness_se); },
                             "float32 (H, W): standard error of the entry's roughness sqrt(alpha_x alpha_y) (-1: not known), "
                             "for a slab material, else None")
      .def_property_readonly("slab_exit_roughness_se",
                             [](const Material& m) { return MapOrNone(m.material().slab_exit_roughness_se); },
                             "float32 (H, W): its standard error (-1: not known), for a slab material, else None")
      .def_property_readonly("slab_internal_reflection",
                             [](const Material& m) { return MapOrNone(m.material().slab_internal_reflection); },
                             "float32 (H, W): weight of the light reflected inside the slab, for a slab material, else None")
      .def_property_readonly("slab_longer_paths",
                             [](const Material& m) { return MapOrNone(m.material().slab_longer_paths); },
                             "float32 (H, W): weight of the longer internal paths' shape, for a slab material, else None")
      .def("eval", &Material::Eval, py::arg("texels"), py::arg("wi"), py::arg("wo"), py::arg("threads") = 0,
           "R(x, i, o) RGB, float64 (N, 3), exactly as `svbtdf eval`. texels: int (N, 2) of (column, row) or (2,); "
           "wi: (N, 3) or (3,) toward the light (z < 0); wo: toward the camera (z > 0); any length, normalised. "
           "Runs on `threads` threads (0: all) without the GIL. Raises svbtdf.InvalidInputError.")
      .def("bsdf_eval", &Material::BsdfEval, py::arg("texels"), py::arg("wi"), py::arg("wo"), py::arg("threads") = 0,
           "The renderer's BSDF f(wi, wo) (render::MaterialSurface, `svbtdf render`), float64 (N, 3); wi and wo "
           "on either side (docs/render.md).")
      .def("sample", &Material::Sample, py::arg("texels"), py::arg("wo"), py::arg("u"), py::arg("threads") = 0,
           "Draws wi from the renderer's BSDF for viewer wo with u = (u_lobe, u1, u2) in [0, 1), (N, 3). Returns "
           "(wi float64 (N, 3), pdf float64 (N,), weight float64 (N, 3) = f |wi.z| / pdf, valid bool (N,)); "
           "invalid draws (no light) are zero.")
      .def("pdf", &Material::Pdf, py::arg("texels"), py::arg("wi"), py::arg("wo"), py::arg("threads") = 0,
           "The solid-angle density, float64 (N,), with which sample(texels, wo, u) returns wi.")
      .def("ndf_cells", &Material::NdfCells, py::arg("column"), py::arg("row"),
           "The texel's normalised NDF D per hemicube cell, float64 (C,), on hemicube_cells(ndf_resolution).")
      .def("ndf_at", &Material::NdfAt, py::arg("column"), py::arg("row"), py::arg("h"),
           "The texel's NDF D(h) at normals h, float64 (N,) for (N, 3) (0 below the horizon).");
}

}  // namespace svbtdf::python
