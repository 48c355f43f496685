// rotorguard._core: the C++ side of the Python package (python/rotorguard/, docs/python.md), its
// parts by topic (bindings.h). Errors are raised as the classes of rotorguard/errors.py, which carry
// file, line and key.
#include <exception>

#include "bindings.h"
#include "rotorguard/io/config_node.h"

namespace rotorguard::python {
namespace {

void TranslateErrors(std::exception_ptr p) {
  // The classes of rotorguard/errors.py, made with the C++ error's fields.
  const auto raise = [](const char* name, py::tuple args) {
    py::object cls = py::module_::import("rotorguard.errors").attr(name);
    py::object error = cls(*args);
    PyErr_SetObject(cls.ptr(), error.ptr());
  };
  try {
    if (p) std::rethrow_exception(p);
  } catch (const io::ConfigError& e) {
    raise("ConfigError", py::make_tuple(e.what(), e.file(), e.line(), e.column(), e.key_path(), e.message()));
  } catch (const io::InputFileError& e) {
    raise("InputFileError", py::make_tuple(e.what(), e.path(), e.reason()));
  } catch (const io::CorruptFileError& e) {
    raise("CorruptFileError", py::make_tuple(e.what(), e.path(), e.byte_offset(), e.message()));
  }
}

}  // namespace
}  // namespace rotorguard::python

PYBIND11_MODULE(_core, m) {
  using namespace rotorguard::python;
  m.doc() = "rotorguard's C++ core: scenarios, flights and their views (use the rotorguard package)";
  py::register_exception_translator(&TranslateErrors);
  BindScenario(m);
  BindCampaigns(m);
  BindFlight(m);
}
