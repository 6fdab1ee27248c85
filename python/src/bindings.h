#pragma once
// The pieces of the svbtdf Python module (docs/python.md), one Bind* per file, and the
// conversions they share. Everything here is glue: what the module computes comes from the
// libraries, exactly as the command line calls them.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "svbtdf/common/image_io.h"
#include "svbtdf/fit/quality.h"
#include "svbtdf/model/vec.h"

namespace svbtdf::python {

namespace py = pybind11;

// C-contiguous float64 and int64 arrays, converted from whatever the caller passed.
using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;
using IntArray = py::array_t<int64_t, py::array::c_style | py::array::forcecast>;

void BindErrors(py::module_& m);
void BindMaterial(py::module_& m);
void BindSession(py::module_& m);
void BindSliceStore(py::module_& m);
void BindStages(py::module_& m);

// A JSON value as the Python object json.loads would give.
py::object ToPython(const nlohmann::json& value);
// A Python object as JSON (through json.dumps).
nlohmann::json ToJson(const py::handle& value);

// A float image as a new float32 array: (height, width) for one channel when `squeeze`, else
// (height, width, channels). Row y of the array is row y of the image (texel index y * width + x).
py::array_t<float> ToArray(const common::FloatImage& image, bool squeeze = true);

// Quality warnings as a list of dicts (stage, file, check, what, figures, likely_cause, line).
py::list ToPython(const std::vector<fit::QualityWarning>& warnings);

// An (N, 3) array of directions (or one (3,) direction for all N when n > 0); throws
// svbtdf::Error(kInvalidInput) naming `name` for any other shape. Returns N.
int64_t DirectionCount(const DoubleArray& directions, const char* name);
model::Vec3 Direction(const DoubleArray& directions, int64_t i);

}  // namespace svbtdf::python
