// Forces written in Python: an adapter that makes an instance of a
// pdyn.Force subclass a pdyn::Force, and the descriptor that lets scenes and
// the conformance kit create them by name, as they create a C++ plugin's.
#pragma once

#include <pybind11/pybind11.h>

#include <memory>
#include <pdyn/force.hpp>
#include <pdyn/host/registry.hpp>
#include <pdyn/plugin.hpp>

namespace pdyn::python {

namespace py = pybind11;

/// Wraps `instance` (a pdyn.Force) as a force object. Its add_forces gets
/// NumPy views of the call's x, v (read-only, N x 3), mass (read-only, N)
/// and f (writable, N x 3), valid during the call only.
std::unique_ptr<Force> make_python_force(py::object instance);

/// The descriptor of the pdyn.Force subclass `cls`, built from its class
/// attributes (name, version, __doc__, parameters, internal, dissipative,
/// singular) once and kept for the life of the process. Throws
/// py::value_error for a declaration pdyn would refuse.
const PluginDescriptor& python_descriptor(py::handle cls);

/// Adds every descriptor python_descriptor() has built to `registry`, with
/// the class's module and name as its origin.
void add_python_plugins(PluginRegistry& registry);

}  // namespace pdyn::python
