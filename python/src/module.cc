// svbtdf._svbtdf: the compiled part of `import svbtdf` (docs/python.md). The package's
// __init__.py re-exports it with the pure-Python helpers.

#include "bindings.h"

PYBIND11_MODULE(_svbtdf, m) {
  m.doc() = "svbtdf: materials, capture sessions, slice stores and the pipeline of thin transparent slabs";
  svbtdf::python::BindErrors(m);
  svbtdf::python::BindMaterial(m);
  svbtdf::python::BindSession(m);
  svbtdf::python::BindSliceStore(m);
  svbtdf::python::BindStages(m);
}
