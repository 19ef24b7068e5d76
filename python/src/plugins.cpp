// pdyn.plugins(), pdyn.describe(), pdyn.check(): the registry and the
// conformance kit from Python.
#include <fmt/format.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <pdyn/conformance.hpp>
#include <pdyn/plugin.hpp>

#include "bindings.hpp"
#include "convert.hpp"
#include "python_force.hpp"

namespace pdyn::python {

std::shared_ptr<PluginRegistry> make_registry(
    const std::vector<std::filesystem::path>& plugin_path) {
  auto registry = std::make_shared<PluginRegistry>();
  registry->discover(PluginRegistry::search_path(plugin_path));
  add_python_plugins(*registry);
  return registry;
}

namespace {

py::dict record_dict(const PluginRecord& r) {
  const PluginDescriptor& d = *r.descriptor;
  py::dict out;
  out["name"] = d.name;
  out["kind"] = kind_name(d.kind);
  out["version"] = d.version;
  out["description"] = d.description;
  out["library"] = r.library.string();
  return out;
}

const PluginRecord& find(const PluginRegistry& registry, const std::string& name) {
  if (const PluginRecord* r = registry.find_any(name)) return *r;
  registry.require_healthy(name);  // a broken library for it: PluginError with its path
  std::vector<std::string> names;
  for (const auto& r : registry.plugins()) names.push_back(r.descriptor->name);
  std::sort(names.begin(), names.end());
  throw PluginError(
      fmt::format("unknown plugin '{}' (expected one of: {})", name, fmt::join(names, ", ")));
}

py::list plugins(const std::vector<std::filesystem::path>& plugin_path) {
  auto registry = make_registry(plugin_path);
  py::list out;
  for (const auto& r : registry->plugins()) out.append(record_dict(r));
  return out;
}

py::dict describe(const std::string& name, const std::vector<std::filesystem::path>& plugin_path) {
  auto registry = make_registry(plugin_path);
  const PluginRecord& r = find(*registry, name);
  py::dict out = record_dict(r);
  py::list params;
  for (const auto& s : r.descriptor->params) {
    py::dict p;
    p["name"] = s.name;
    p["type"] = type_name(s.type);
    p["unit"] = s.unit;
    p["doc"] = s.doc;
    p["required"] = s.required;
    p["default"] = s.fallback ? to_python(*s.fallback) : py::none();
    p["min"] = s.min ? py::cast(*s.min) : py::none();
    p["max"] = s.max ? py::cast(*s.max) : py::none();
    params.append(p);
  }
  out["parameters"] = params;
  if (r.descriptor->kind == PluginKind::Force) {
    const ForceTraits& t = r.descriptor->force_traits;
    out["traits"] =
        py::dict(py::arg("internal") = t.internal, py::arg("dissipative") = t.dissipative,
                 py::arg("singular") = t.singular);
  }
  return out;
}

// The kit's report: (name, verdict, measured, bound, detail) per check, and
// the table `pdyn check` prints.
py::tuple check(py::object target, const std::vector<std::filesystem::path>& plugin_path,
                std::uint64_t seed) {
  conformance::Options options;
  options.seed = seed;
  const PluginDescriptor* d = nullptr;
  std::shared_ptr<PluginRegistry> registry;  // keeps a library loaded while checked
  if (py::isinstance<py::type>(target)) {
    d = &python_descriptor(target);
  } else {
    registry = std::make_shared<PluginRegistry>();
    const std::string text = py::str(target).cast<std::string>();
    const std::filesystem::path path = text;
    if (path.extension() == ".so") {
      if (!registry->load_library(path)) {
        throw PluginError(fmt::format("{}: {}", path.string(), registry->faults().back().message));
      }
      d = registry->plugins().back().descriptor;
    } else {
      registry = make_registry(plugin_path);
      d = find(*registry, text).descriptor;
    }
    // A C++ plugin runs isolated, as under `pdyn check`: one that crashes
    // fails its check instead of taking the interpreter down.
    options.isolate = true;
  }
  std::vector<conformance::CheckResult> results;
  {
    py::gil_scoped_release release;
    results = conformance::run_checks(*d, options);
  }
  py::list rows;
  for (const auto& r : results) {
    rows.append(py::make_tuple(r.name, conformance::verdict_name(r.verdict), r.measured, r.bound,
                               r.detail));
  }
  return py::make_tuple(d->name, rows, conformance::table(results));
}

}  // namespace

void bind_plugins(py::module_& m) {
  m.def("_plugins", &plugins);
  m.def("_plugin_folder_problem",
        [](const std::filesystem::path& dir) { return PluginRegistry::folder_problem(dir); });
  m.def("_describe", &describe);
  m.def("_check", &check);
}

}  // namespace pdyn::python
