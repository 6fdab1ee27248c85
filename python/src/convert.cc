#include <algorithm>

#include "bindings.h"
#include "svbtdf/common/error.h"

namespace svbtdf::python {

py::object ToPython(const nlohmann::json& value) {
  return py::module_::import("json").attr("loads")(value.dump());
}

nlohmann::json ToJson(const py::handle& value) {
  return nlohmann::json::parse(py::module_::import("json").attr("dumps")(value).cast<std::string>());
}

py::array_t<float> ToArray(const common::FloatImage& image, bool squeeze) {
  std::vector<py::ssize_t> shape = {image.height, image.width};
  if (!squeeze || image.channels != 1) shape.push_back(image.channels);
  py::array_t<float> array(shape);
  std::copy(image.pixels.begin(), image.pixels.end(), array.mutable_data());
  return array;
}

py::list ToPython(const std::vector<fit::QualityWarning>& warnings) {
  py::list out;
  for (const fit::QualityWarning& w : warnings) {
    py::dict d;
    d["stage"] = w.stage;
    d["file"] = w.file;
    d["check"] = w.check;
    d["what"] = w.what;
    d["figures"] = w.figures;
    d["likely_cause"] = w.likely_cause;
    d["line"] = w.Line();
    out.append(d);
  }
  return out;
}

int64_t DirectionCount(const DoubleArray& directions, const char* name) {
  if (directions.ndim() == 1 && directions.shape(0) == 3) return 1;
  if (directions.ndim() == 2 && directions.shape(1) == 3) return directions.shape(0);
  common::ThrowInvalidInput(name, "must be an array of shape (N, 3) or (3,)");
}

model::Vec3 Direction(const DoubleArray& directions, int64_t i) {
  const double* p = directions.data() + (directions.ndim() == 1 ? 0 : 3 * i);
  return model::Vec3(p[0], p[1], p[2]);
}

}  // namespace svbtdf::python
