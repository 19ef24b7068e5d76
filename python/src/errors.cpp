// pdyn's C++ exceptions as the Python exceptions of pdyn/errors.py, with
// the located diagnostics as attributes.
#include <pybind11/stl.h>

#include <pdyn/host/checkpoint.hpp>
#include <pdyn/host/scene.hpp>
#include <pdyn/host/simulation.hpp>

#include "bindings.hpp"

namespace pdyn::python {

namespace {

py::object error_type(const char* name) { return py::module_::import("pdyn.errors").attr(name); }

void raise(const char* type_name, const std::exception& e, const py::dict& attributes = {}) {
  py::object type = error_type(type_name);
  py::object exc = type(e.what());
  for (const auto& [key, value] : attributes) exc.attr(key) = value;
  PyErr_SetObject(type.ptr(), exc.ptr());
}

// "FILE:LINE:COLUMN" into its parts; a location without line and column
// (a file that cannot be read, a --set override) keeps them None.
py::tuple split_location(const std::string& location) {
  const auto c2 = location.rfind(':');
  if (c2 != std::string::npos && c2 > 0) {
    const auto c1 = location.rfind(':', c2 - 1);
    if (c1 != std::string::npos) {
      try {
        std::size_t used1 = 0, used2 = 0;
        const std::string l = location.substr(c1 + 1, c2 - c1 - 1), c = location.substr(c2 + 1);
        const int line = std::stoi(l, &used1), column = std::stoi(c, &used2);
        if (used1 == l.size() && used2 == c.size()) {
          return py::make_tuple(location.substr(0, c1), line, column);
        }
      } catch (const std::exception&) {
      }
    }
  }
  return py::make_tuple(location, py::none(), py::none());
}

}  // namespace

void bind_errors(py::module_&) {
  // pybind11's translator type (ExceptionTranslator) takes the pointer by value.
  // NOLINTNEXTLINE(performance-unnecessary-value-param)
  py::register_exception_translator([](std::exception_ptr p) {
    if (!p) return;
    try {
      std::rethrow_exception(p);
    } catch (const SceneError& e) {
      py::list diags;
      for (const auto& d : e.diagnostics()) {
        const py::tuple where = split_location(d.location);
        diags.append(py::make_tuple(d.location, d.message, where[0], where[1], where[2]));
      }
      py::dict a;
      a["diagnostics"] = diags;
      const py::tuple first = e.diagnostics().empty()
                                  ? py::make_tuple(py::none(), py::none(), py::none())
                                  : split_location(e.diagnostics()[0].location);
      a["file"] = first[0];
      a["line"] = first[1];
      a["column"] = first[2];
      raise("SceneError", e, a);
    } catch (const StepError& e) {
      const StepFault& f = e.fault();
      py::dict a;
      a["label"] = f.label.empty() ? py::object(py::none()) : py::object(py::str(f.label));
      a["non_finite"] =
          f.kind == StepFault::Kind::NonFiniteForce || f.kind == StepFault::Kind::NonFiniteState;
      a["particle"] = f.particle >= 0 ? py::object(py::int_(f.particle)) : py::object(py::none());
      raise("StepError", e, a);
    } catch (const CheckpointError& e) {
      raise("CheckpointError", e);
    } catch (const PluginError& e) {
      raise("PluginError", e);
    } catch (const Error& e) {
      raise("Error", e);
    }
  });
}

}  // namespace pdyn::python
