// svbtdf::common::Error as Python exceptions: one class per ErrorKind under svbtdf.Error, each
// also a subclass of the built-in exception a Python user would catch for it (ValueError for bad
// input and bad files, OSError for I/O, KeyboardInterrupt for an interruption), so that
// `except ValueError` and `except svbtdf.FormatError` both work. The message is the command
// line's one line (without "svbtdf: error: "), naming the file or argument at fault.

#include "bindings.h"
#include "svbtdf/common/error.h"

namespace svbtdf::python {
namespace {

struct ErrorClass {
  common::ErrorKind kind;
  const char* name;
  PyObject* builtin;  // the second base, or null
  const char* doc;
  PyObject* type = nullptr;
};

ErrorClass g_classes[] = {
    {common::ErrorKind::kInvalidInput, "InvalidInputError", PyExc_ValueError,
     "A bad argument, or a bad value in a file the user handed in (exit code 2 on the command line)."},
    {common::ErrorKind::kFormat, "FormatError", PyExc_ValueError,
     "A file that cannot be parsed or has the wrong version or shape."},
    {common::ErrorKind::kIo, "IoError", PyExc_OSError, "A file or folder that cannot be read or written."},
    {common::ErrorKind::kHardware, "HardwareError", nullptr, "A camera or display that failed or vanished."},
    {common::ErrorKind::kNumerical, "NumericalError", PyExc_ArithmeticError,
     "A computation that did not converge or produced non-finite values."},
    {common::ErrorKind::kInterrupted, "Interrupted", PyExc_KeyboardInterrupt,
     "The user stopped the work (Ctrl-C); what was done is kept and the same call resumes it."},
};
PyObject* g_error = nullptr;

const char* KindName(common::ErrorKind kind) {
  switch (kind) {
    case common::ErrorKind::kInvalidInput: return "invalid_input";
    case common::ErrorKind::kFormat: return "format";
    case common::ErrorKind::kIo: return "io";
    case common::ErrorKind::kHardware: return "hardware";
    case common::ErrorKind::kNumerical: return "numerical";
    case common::ErrorKind::kInterrupted: return "interrupted";
  }
  return "unknown";
}

void Raise(const common::Error& error) {
  PyObject* type = g_error;
  for (const ErrorClass& c : g_classes) {
    if (c.kind == error.kind()) type = c.type;
  }
  py::object instance = py::reinterpret_steal<py::object>(PyObject_CallFunction(type, "s", error.what()));
  if (!instance) return;  // the call set its own Python error
  instance.attr("kind") = KindName(error.kind());
  instance.attr("subject") = error.subject();
  instance.attr("problem") = error.problem();
  instance.attr("hint") = error.hint();
  PyErr_SetObject(type, instance.ptr());
}

}  // namespace

void BindErrors(py::module_& m) {
  g_error = PyErr_NewExceptionWithDoc(
      "svbtdf.Error",
      "Base of every svbtdf error. str(e) is the command line's one-line message, naming the file or "
      "argument at fault; e.kind, e.subject, e.problem and e.hint hold its parts.",
      PyExc_Exception, nullptr);
  m.add_object("Error", py::handle(g_error));
  for (ErrorClass& c : g_classes) {
    py::tuple bases = c.builtin ? py::make_tuple(py::handle(g_error), py::handle(c.builtin)) : py::make_tuple(py::handle(g_error));
    c.type = PyErr_NewExceptionWithDoc((std::string("svbtdf.") + c.name).c_str(), c.doc, bases.ptr(), nullptr);
    if (!c.type) throw py::error_already_set();
    m.add_object(c.name, py::handle(c.type));
  }
  py::register_exception_translator([](std::exception_ptr thrown) {
    try {
      if (thrown) std::rethrow_exception(thrown);
    } catch (const common::Error& error) {
      Raise(error);
    }
  });
}

}  // namespace svbtdf::python
