// The parts of the pdyn Python module (_pdyn), each bound by one file.
#pragma once

#include <pybind11/pybind11.h>

#include <filesystem>
#include <memory>
#include <pdyn/host/registry.hpp>
#include <vector>

namespace pdyn::python {

namespace py = pybind11;

/// A registry of the plugins on the search path (`plugin_path` first, then
/// $PDYN_PLUGIN_PATH and the installed plugins) and of the Python forces
/// declared so far.
std::shared_ptr<PluginRegistry> make_registry(
    const std::vector<std::filesystem::path>& plugin_path);

void bind_errors(py::module_& m);        // errors.cpp
void bind_simulation(py::module_& m);    // simulation.cpp
void bind_plugins(py::module_& m);       // plugins.cpp
void bind_python_force(py::module_& m);  // python_force.cpp

}  // namespace pdyn::python
