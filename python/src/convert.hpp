// Conversions between Python objects and pdyn's values, and the NumPy views
// of the particle store that the module hands out.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <pdyn/params.hpp>
#include <pdyn/types.hpp>

namespace pdyn::python {

namespace py = pybind11;

/// A NumPy array of `shape` float64 over `data` (not copied): C order, rows
/// of `shape[1]` values, as a 3 x N Eigen matrix lies in memory. `base` keeps
/// the memory alive. Writable unless `readonly`.
py::array view(const double* data, std::vector<py::ssize_t> shape, py::handle base, bool readonly);
/// The same over N bytes, as NumPy bool (pdyn's 0/1 flags).
py::array bool_view(const std::uint8_t* data, py::ssize_t n, py::handle base);
/// Makes an array read-only (NumPy then refuses writes with its own error).
void set_readonly(py::handle array);

/// A parameter value as Python sees it: numbers, strings, lists of 3 floats
/// for vectors, NumPy arrays for lists (index pairs: int64 (M, 2)), dicts
/// for named reals.
py::object to_python(const ParamValue& value);
/// A Python value as a parameter of `type` (for defaults a Python force
/// declares). Throws py::type_error naming `what` if it does not fit.
ParamValue from_python(ParamType type, py::handle value, const std::string& what);
/// "real", "integer", ... as pdyn.param(type=...) spells them.
ParamType param_type(const std::string& name);

}  // namespace pdyn::python
