// Forces written in Python (python_force.hpp).
#include "python_force.hpp"

#include <fmt/format.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <map>

#include "bindings.hpp"
#include "convert.hpp"

namespace pdyn::python {

namespace {

// A Python exception as one line for the message that names the force: its
// type and text (the traceback stays with Python's own report).
std::string describe(const py::error_already_set& e) {
  std::string text = e.what();
  if (const auto at = text.find("\n\nAt:"); at != std::string::npos) text.resize(at);
  return text;
}

class PythonForce final : public Force {
 public:
  explicit PythonForce(py::object instance)
      : instance_(std::move(instance)),
        add_forces_(instance_.attr("add_forces")),
        has_potential_(
            !instance_.attr("potential_energy")
                 .attr("__func__")
                 .is(py::module_::import("pdyn").attr("Force").attr("potential_energy"))),
        // Per object, so that __init__ may decide from the parameters (a
        // damping of 0 reads no velocity).
        dependence_{instance_.attr("reads_velocity").cast<bool>(),
                    instance_.attr("reads_time").cast<bool>()} {}

  StateDependence dependence() const override { return dependence_; }

  // Acquiring the GIL throws only if Python cannot make a thread state, where
  // terminating is all that is left.
  // NOLINTNEXTLINE(bugprone-exception-escape)
  ~PythonForce() override {
    // The kit and a released-GIL step may destroy it on any thread.
    py::gil_scoped_acquire gil;
    add_forces_ = py::object();
    instance_ = py::object();
  }

  void add_forces(const ParticleView& p, Eigen::Ref<Matrix3X> f) override {
    if (f.outerStride() != 3) throw Error("python force: f is not a contiguous 3 x N matrix");
    py::gil_scoped_acquire gil;
    std::string failure;
    try {
      const py::ssize_t n = p.size();
      py::none base;
      py::array x = view(p.x.data(), {n, 3}, base, true);
      py::array v = view(p.v.data(), {n, 3}, base, true);
      py::array m = view(p.mass.data(), {n}, base, true);
      py::array fv = view(f.data(), {n, 3}, base, false);
      instance_.attr("t") = p.t;
      add_forces_(x, v, m, fv);
      // The views point into the store only during the call: one kept
      // beyond it (self.x = x) would read freed or changed memory later.
      for (const py::array* a : {&x, &v, &m, &fv}) {
        if (Py_REFCNT(a->ptr()) > 1) {
          failure =
              "add_forces kept a reference to one of its arrays (expected x, v, mass "
              "and f to be used during the call only: keep a copy, x.copy())";
        }
      }
    } catch (py::error_already_set& e) {
      failure = describe(e);
    }
    if (!failure.empty()) throw Error(failure);
  }

  std::optional<double> potential_energy(const ParticleView& p) const override {
    if (!has_potential_) return std::nullopt;
    py::gil_scoped_acquire gil;
    std::string failure;
    try {
      const py::ssize_t n = p.size();
      py::none base;
      const py::object u = instance_.attr("potential_energy")(view(p.x.data(), {n, 3}, base, true),
                                                              view(p.v.data(), {n, 3}, base, true),
                                                              view(p.mass.data(), {n}, base, true));
      if (u.is_none()) return std::nullopt;
      return u.cast<double>();
    } catch (py::error_already_set& e) {
      failure = describe(e);
    } catch (const py::cast_error&) {
      failure =
          "potential_energy returned something that is not a number (expected a float, "
          "J, or None)";
    }
    throw Error(failure);
  }

 private:
  py::object instance_;
  py::object add_forces_;
  bool has_potential_;
  StateDependence dependence_;
};

// Descriptors of Python forces live as long as the process: registries,
// scenes and conformance runs hold pointers to them. Leaked on purpose, so
// that no Python object is released after the interpreter has finished.
std::map<std::string, std::unique_ptr<PluginDescriptor>>& descriptors() {
  static auto* all = new std::map<std::string, std::unique_ptr<PluginDescriptor>>();
  return *all;
}

std::string origin_of(py::handle cls) {
  return fmt::format("<python {}.{}>", cls.attr("__module__").cast<std::string>(),
                     cls.attr("__qualname__").cast<std::string>());
}

ParamSpec make_spec(const std::string& name, py::handle p) {
  ParamSpec s;
  s.name = name;
  s.type = param_type(p.attr("type").cast<std::string>());
  s.unit = p.attr("unit").cast<std::string>();
  s.doc = p.attr("doc").cast<std::string>();
  s.required = p.attr("required").cast<bool>();
  const std::string what = fmt::format("parameter '{}'", name);
  if (!p.attr("default").is_none()) s.fallback = from_python(s.type, p.attr("default"), what);
  if (!p.attr("sample").is_none()) s.sample = from_python(s.type, p.attr("sample"), what);
  if (!p.attr("min").is_none()) s.min = p.attr("min").cast<double>();
  if (!p.attr("max").is_none()) s.max = p.attr("max").cast<double>();
  return s;
}

}  // namespace

std::unique_ptr<Force> make_python_force(py::object instance) {
  return std::make_unique<PythonForce>(std::move(instance));
}

const PluginDescriptor& python_descriptor(py::handle cls) {
  const std::string origin = origin_of(cls);
  auto& all = descriptors();
  if (const auto it = all.find(origin); it != all.end()) return *it->second;
  auto d = std::make_unique<PluginDescriptor>();
  d->kind = PluginKind::Force;
  d->name = cls.attr("plugin_name")().cast<std::string>();
  d->version = py::str(cls.attr("version")).cast<std::string>();
  d->description = cls.attr("description")().cast<std::string>();
  for (const auto& [key, spec] : cls.attr("parameters").cast<py::dict>()) {
    d->params.push_back(make_spec(key.cast<std::string>(), spec));
  }
  d->force_traits.internal = cls.attr("internal").cast<bool>();
  d->force_traits.dissipative = cls.attr("dissipative").cast<bool>();
  d->force_traits.singular = cls.attr("singular").cast<bool>();
  // The factory builds the class with the checked parameters as keywords.
  py::object klass = py::reinterpret_borrow<py::object>(cls);
  auto* held = new py::object(klass);  // released never: see descriptors()
  d->create_force = [held](const Params& p, const SceneContext&) -> std::unique_ptr<Force> {
    py::gil_scoped_acquire gil;
    std::string failure;
    try {
      py::dict kwargs;
      for (const auto& [key, value] : p.values()) kwargs[py::str(key)] = to_python(value);
      return make_python_force((*held)(**kwargs));
    } catch (py::error_already_set& e) {
      failure = describe(e);
    }
    throw Error(failure);
  };
  // The registry's own checks (name, parameters) apply when it is added;
  // a refused declaration is reported now, where the class is given.
  PluginRegistry probe;
  if (!probe.add(*d, origin)) {
    throw py::value_error(fmt::format(
        "{}: {}", origin, probe.faults().empty() ? "refused" : probe.faults()[0].message));
  }
  return *all.emplace(origin, std::move(d)).first->second;
}

void add_python_plugins(PluginRegistry& registry) {
  for (const auto& [origin, d] : descriptors()) {
    // Those it already has (a registry is refreshed before each add_force).
    const PluginRecord* known = registry.find(d->kind, d->name);
    if (!known || known->descriptor != d.get()) registry.add(*d, origin);
  }
}

void bind_python_force(py::module_& m) {
  m.def(
      "_register_force", [](py::handle cls) { return python_descriptor(cls).name; },
      "Builds (once) the descriptor of a pdyn.Force subclass; returns its plugin name.");
}

}  // namespace pdyn::python
