// svbtdf.SliceStore: a processed session (docs/slice-store.md) through fit::SliceStore, the
// reader `svbtdf fit` uses.

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "bindings.h"
#include "svbtdf/common/error.h"
#include "svbtdf/fit/fit_material.h"
#include "svbtdf/fit/slice_store.h"

namespace svbtdf::python {
namespace {

int64_t TexelIndex(const fit::SliceStore& store, int col, int row) {
  const fit::SliceStoreInfo& info = store.info();
  if (col < 0 || row < 0 || col >= info.texels_x || row >= info.texels_y) {
    common::ThrowInvalidInput("texel", "(" + std::to_string(col) + ", " + std::to_string(row) + ") is outside the " +
                                           std::to_string(info.texels_x) + "x" + std::to_string(info.texels_y) +
                                           " slice store");
  }
  return static_cast<int64_t>(row) * info.texels_x + col;
}

// The dots a fit withheld: those a material records (provenance "holdout"), else fit::HeldOutDots
// of `holdout` and `seed` as `svbtdf fit --holdout --seed` chose them.
std::vector<bool> HeldOut(const fit::SliceStore& store, const py::object& held_out_dots, double holdout, uint64_t seed) {
  const int dots = store.info().num_dots;
  std::vector<int> chosen = held_out_dots.is_none() ? fit::HeldOutDots(dots, holdout, seed)
                                                    : held_out_dots.cast<std::vector<int>>();
  std::vector<bool> flags(dots, false);
  for (const int q : chosen) {
    if (q < 0 || q >= dots) common::ThrowInvalidInput("held_out_dots", "lists dot " + std::to_string(q) + ", not one of the store's " + std::to_string(dots));
    flags[q] = true;
  }
  return flags;
}

py::dict Samples(const fit::SliceStore& store, int col, int row, const py::object& held_out_dots, double holdout,
                 uint64_t seed) {
  const int64_t texel = TexelIndex(store, col, row);
  const int dots = store.info().num_dots;
  const std::vector<bool> held_out = HeldOut(store, held_out_dots, holdout, seed);
  std::vector<float> rgb;
  store.ReadSamples(texel, &rgb);
  py::array_t<double> lights({dots, 3});
  py::array_t<float> values({dots, 3});
  py::array_t<bool> flags(dots), valid(dots);
  for (int q = 0; q < dots; ++q) {
    const model::Vec3 light = store.geometry().Light(texel, q);
    bool finite = true;
    for (int c = 0; c < 3; ++c) {
      lights.mutable_data()[3 * q + c] = light[c];
      values.mutable_data()[3 * q + c] = rgb[3 * q + c];
      finite = finite && std::isfinite(rgb[3 * q + c]);
    }
    flags.mutable_data()[q] = held_out[q];
    valid.mutable_data()[q] = finite;
  }
  const model::Vec3 view = store.geometry().View(texel);
  py::dict d;
  d["texel"] = py::make_tuple(col, row);
  d["light"] = lights;
  d["view"] = py::make_tuple(view.x(), view.y(), view.z());
  d["values"] = values;
  d["valid"] = valid;
  d["held_out"] = flags;
  return d;
}

py::dict Info(const fit::SliceStore& store) {
  const fit::SliceStoreInfo& info = store.info();
  py::dict d;
  d["texels_x"] = info.texels_x;
  d["texels_y"] = info.texels_y;
  d["num_dots"] = info.num_dots;
  d["light_resolution"] = info.light_resolution;
  d["tile_texels"] = info.tile_texels;
  d["eta"] = info.eta;
  d["white_exitance_noise"] = py::make_tuple(info.white_exitance_noise[0], info.white_exitance_noise[1],
                                             info.white_exitance_noise[2]);
  d["sample_size"] = py::make_tuple(store.geometry().width_m, store.geometry().height_m);
  d["provenance"] = ToPython(info.provenance);
  return d;
}

}  // namespace

void BindSliceStore(py::module_& m) {
  py::class_<fit::SliceStore>(m, "SliceStore",
                              "A processed session (docs/slice-store.md): every texel's BTDF samples and the maps. "
                              "Open with SliceStore.open(path).")
      .def_static("open", [](const std::string& path) { return std::make_unique<fit::SliceStore>(fit::SliceStore::Open(path)); },
                  py::arg("path"), "Opens and checks PROCESSED/. Raises svbtdf.FormatError or svbtdf.IoError naming the file.")
      .def_property_readonly("path", [](const fit::SliceStore& s) { return s.folder().string(); })
      .def_property_readonly("info", &Info,
                             "dict: texels_x, texels_y, num_dots, light_resolution, tile_texels, eta (0: unknown), "
                             "sample_size (m), provenance")
      .def_property_readonly("rho_d", [](const fit::SliceStore& s) { return ToArray(s.rho_d()); }, "float32 (H, W, 3)")
      .def_property_readonly("mask", [](const fit::SliceStore& s) { return ToArray(s.mask()); },
                             "float32 (H, W): 1 where the texel has enough valid samples to be fitted")
      .def_property_readonly("reach", [](const fit::SliceStore& s) { return ToArray(s.reach()); },
                             "float32 (H, W): 1 where a dot lies beneath the texel")
      .def("samples", &Samples, py::arg("column"), py::arg("row"), py::arg("held_out_dots") = py::none(),
           py::arg("holdout") = 0.0, py::arg("seed") = 1,
           "One texel's samples, a dict: light float64 (Q, 3) (toward each dot, z < 0), view (x, y, z) toward the "
           "camera, values float32 (Q, 3) RGB R(x, i_q, o) (NaN: no valid measurement), valid bool (Q,), held_out "
           "bool (Q,): the dots in held_out_dots (e.g. material.provenance['holdout']['dots']), else those "
           "`svbtdf fit --holdout HOLDOUT --seed SEED` withholds.")
      .def("slice", [](const fit::SliceStore& s, int col, int row) {
            py::array_t<float> out(s.light_grid().num_cells());
            s.ReadSlice(TexelIndex(s, col, row), out.mutable_data());
            return out;
          }, py::arg("column"), py::arg("row"),
          "The texel's refractive luminance resampled on the light hemicube, float32 (C,) over "
          "hemicube_cells(info['light_resolution']) flipped to z < 0.");
}

}  // namespace svbtdf::python
