// pdyn.Simulation: a scene stepped from Python, its state as NumPy views of
// the particle store.
#include <fmt/format.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <atomic>
#include <cmath>
#include <mutex>
#include <pdyn/host/assembly.hpp>
#include <pdyn/host/registry.hpp>
#include <pdyn/host/simulation.hpp>
#include <pdyn/host/threads.hpp>
#include <pdyn/thermo.hpp>
#include <thread>

#include "bindings.hpp"
#include "convert.hpp"
#include "python_force.hpp"

namespace pdyn::python {

namespace {

// Ctrl-C while the simulation steps with the GIL released: asked every few
// steps; Python's KeyboardInterrupt is raised once the step returns.
bool interrupted() {
  py::gil_scoped_acquire gil;
  return PyErr_CheckSignals() != 0;
}

// One Python thread at a time inside a simulation. Stepping releases the
// GIL, so without this two threads (a GUI and a worker, a thread pool) would
// step, add to or restore one System at once and corrupt its memory. Every
// call into a simulation holds its Turn for the whole call: a second thread
// waits for it, a call from inside a call on the same thread (a Python
// force that steps the simulation it belongs to) is refused. Distinct
// simulations have distinct locks and step in parallel.
class CallLock {
 public:
  class Turn {
   public:
    explicit Turn(CallLock& owner) : owner_(&owner), lock_(owner.mutex_, std::defer_lock) {}
    Turn(Turn&& other) noexcept = default;
    ~Turn() {
      if (lock_.owns_lock()) owner_->holder_.store(std::thread::id());
    }

   private:
    friend class CallLock;
    CallLock* owner_;
    std::unique_lock<std::mutex> lock_;
  };

  // Waits with the GIL released: the thread inside may need the GIL to
  // finish its call (a Python force, Ctrl-C), and holding it while waiting
  // would deadlock. Lock order is always this mutex, then the GIL.
  Turn enter(const char* call) {
    if (holder_.load() == std::this_thread::get_id()) {
      throw std::runtime_error(fmt::format(
          "{}: called from inside another call into the same simulation on this thread (a "
          "Python force or callback cannot step, change or read the simulation that is calling "
          "it; expected the call after the step returns)",
          call));
    }
    Turn turn(*this);
    if (!turn.lock_.try_lock()) {
      py::gil_scoped_release release;
      turn.lock_.lock();
    }
    holder_.store(std::this_thread::get_id());
    return turn;
  }

 private:
  std::mutex mutex_;
  std::atomic<std::thread::id> holder_{};
};

class PySimulation {
 public:
  PySimulation(std::shared_ptr<PluginRegistry> registry, Scene scene, int threads)
      : registry_(std::move(registry)), sim_(std::move(scene), threads) {}

  // Every binding below enters first (CallLock). The thread count is set
  // again on each entry: OpenMP keeps it per calling thread, and a Python
  // thread other than the one that loaded the simulation would otherwise
  // step with the process's default.
  CallLock::Turn enter(const char* call) {
    CallLock::Turn turn = lock_.enter(call);
    set_threads(sim_.threads());
    return turn;
  }

  Simulation& sim() { return sim_; }
  System& sys() { return sim_.system(); }

  // ---- views of the store ----
  py::array track(py::array a) {
    // Prune dead views now and then, so that reading sim.x in a loop does
    // not grow the list.
    if (views_.size() >= 2 * live_ + 16) {
      std::erase_if(views_, [](const py::weakref& w) { return w().is_none(); });
      live_ = views_.size();
    }
    views_.emplace_back(a);
    return a;
  }
  py::array positions(py::handle self) {
    return track(view(sys().positions().data(), {sys().size(), 3}, self, false));
  }
  py::array velocities(py::handle self) {
    return track(view(sys().velocities().data(), {sys().size(), 3}, self, false));
  }
  py::array masses(py::handle self) {
    return track(view(sys().masses().data(), {sys().size()}, self, true));
  }
  py::array forces(py::handle self) {
    return track(view(sys().forces().data(), {sys().forces().cols(), 3}, self, true));
  }
  py::array fixed(py::handle self) {
    return track(bool_view(sys().fixed().data(), sys().size(), self));
  }

  // Adding particles replaces the store: the old one is kept (and its views
  // made read-only) while any view of it lives, so none ever dangles.
  void add_particles(py::array_t<double, py::array::c_style | py::array::forcecast> x, py::object v,
                     py::object mass, py::object fixed) {
    const py::ssize_t n = check_rows(x, "x");
    auto xs = Eigen::Map<const Matrix3X>(x.data(), 3, n);
    Matrix3X vs = Matrix3X::Zero(3, n);
    if (!v.is_none()) {
      auto va = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(v);
      if (!va || check_rows(va, "v") != n) {
        throw py::value_error(fmt::format("v: expected the shape ({}, 3) of x", n));
      }
      vs = Eigen::Map<const Matrix3X>(va.data(), 3, n);
    }
    Eigen::VectorXd m = Eigen::VectorXd::Ones(n);
    if (!mass.is_none()) {
      auto ma = py::array_t<double, py::array::forcecast>::ensure(mass);
      if (!ma) throw py::type_error("mass: expected a number or an array of numbers, kg");
      if (ma.ndim() == 0) {
        m.setConstant(*ma.data());
      } else if (ma.ndim() == 1 && ma.shape(0) == n) {
        m = Eigen::Map<const Eigen::VectorXd>(ma.data(), n);
      } else {
        throw py::value_error(fmt::format("mass: expected a number or {} numbers (kg)", n));
      }
    }
    for (Index i = 0; i < n; ++i) {
      if (!(m(i) > 0) || !std::isfinite(m(i))) {
        throw py::value_error(
            fmt::format("mass[{}] = {} kg (expected a finite mass > 0)", i, m(i)));
      }
    }
    if (!xs.allFinite() || !vs.allFinite()) {
      throw py::value_error("x, v: non-finite values (expected finite positions and velocities)");
    }
    std::vector<std::uint8_t> f(static_cast<std::size_t>(n), 0);
    if (!fixed.is_none()) {
      auto fa = py::array_t<bool, py::array::forcecast>::ensure(fixed);
      if (!fa) throw py::type_error("fixed: expected a bool or an array of bools");
      for (py::ssize_t i = 0; i < n; ++i) {
        f[static_cast<std::size_t>(i)] = fa.ndim() == 0 ? *fa.data() : fa.data()[i];
      }
      if (fa.ndim() != 0 && (fa.ndim() != 1 || fa.shape(0) != n)) {
        throw py::value_error(fmt::format("fixed: expected a bool or {} bools", n));
      }
    }
    auto old = sim_.add_particles(xs, vs, m, f);
    std::erase_if(retired_, [](const Retired& r) { return !r.alive(); });
    Retired r{std::move(old), std::move(views_)};
    views_.clear();
    live_ = 0;
    for (const auto& w : r.views) {
      if (py::object a = w(); !a.is_none()) set_readonly(a);
    }
    if (r.alive()) retired_.push_back(std::move(r));
  }

  static py::ssize_t check_rows(const py::array& a, const char* name) {
    if (a.ndim() == 1 && a.shape(0) == 3) {
      throw py::value_error(
          fmt::format("{}: shape (3,) (expected (n, 3): one row per particle; "
                      "for one particle, [[x, y, z]])",
                      name));
    }
    if (a.ndim() != 2 || a.shape(1) != 3) {
      std::string shape;
      for (py::ssize_t i = 0; i < a.ndim(); ++i)
        shape += (i ? ", " : "") + std::to_string(a.shape(i));
      throw py::value_error(
          fmt::format("{}: shape ({}) (expected (n, 3): one row per particle)", name, shape));
    }
    return a.shape(0);
  }

  // ---- stepping ----
  std::int64_t step(std::int64_t n) {
    if (n < 0) throw py::value_error(fmt::format("step({}): expected a count >= 0", n));
    touch_if_viewed();
    return released([&] { return sim_.step(n, interrupted); });
  }
  std::int64_t run_until(double t, std::int64_t max_steps) {
    touch_if_viewed();
    return released([&] { return sim_.run_until(t, max_steps, interrupted); });
  }
  std::int64_t run_to_end() {
    touch_if_viewed();
    return released([&] { return sim_.run_to_end(interrupted); });
  }

  // The views of positions and velocities are writable, and a write through
  // one is invisible to the kernel. While any lives, each stepping call marks
  // the state as changed (System::touch): the Stepper then copies its last
  // good state afresh and a solver that keeps forces (verlet) evaluates them
  // again, as after any other write.
  void touch_if_viewed() {
    for (const auto& w : views_) {
      const py::object a = w();
      if (!a.is_none() && py::reinterpret_borrow<py::array>(a).writeable()) {
        sys().touch();
        return;
      }
    }
  }

  // Steps with the GIL released; a Ctrl-C seen meanwhile is raised after.
  template <class Steps>
  static std::int64_t released(const Steps& steps) {
    std::int64_t taken;
    {
      py::gil_scoped_release release;
      taken = steps();
    }
    if (PyErr_Occurred()) throw py::error_already_set();
    return taken;
  }

  // ---- plugin objects ----
  std::string add_plugin(PluginKind kind, const std::string& yaml, const std::string& call) {
    // Python forces declared since the scene was loaded are known by name too.
    add_python_plugins(*registry_);
    const std::string origin = fmt::format("{} #{}", call, ++calls_);
    std::string label = pdyn::add_plugin(sim_.scene(), *registry_, kind, yaml, origin);
    if (kind == PluginKind::Solver) sim_.solver_changed();
    return label;
  }
  std::string add_python_force(py::object instance) {
    py::handle cls = py::type::handle_of(instance);
    const PluginDescriptor& d = python_descriptor(cls);
    std::string label = fmt::format("{} (add_force #{})", d.name, ++calls_);
    SystemAssembly(sys()).add_force(make_python_force(std::move(instance)), label);
    sim_.scene().force_traits[label] = d.force_traits;
    return label;
  }
  void remove(const std::string& label) {
    Scene& scene = sim_.scene();
    for (const auto& f : sys().force_objects()) {
      if (f.label == label) {
        SystemAssembly(sys()).remove_force(f.force.get());
        scene.force_traits.erase(label);
        forget(label);
        return;
      }
    }
    for (const auto& c : sys().collider_objects()) {
      if (c.label == label) {
        SystemAssembly(sys()).remove_collider(c.collider.get());
        forget(label);
        return;
      }
    }
    // The kernel cannot take a constraint out of a system (its rows size the
    // constraint force's matrices): say so rather than "no such label".
    for (const auto& c : sys().constraint_objects()) {
      if (c.label == label) {
        throw py::key_error(
            fmt::format("'{}' is a constraint, which cannot be removed (expected the label of a "
                        "force or collider: {})",
                        label, fmt::join(labels(), ", ")));
      }
    }
    throw py::key_error(fmt::format("no force or collider is labelled '{}' (expected one of: {})",
                                    label, fmt::join(labels(), ", ")));
  }
  std::vector<std::string> labels() const {
    std::vector<std::string> out;
    for (const auto& f : sim_.system().force_objects()) out.push_back(f.label);
    for (const auto& c : sim_.system().collider_objects()) out.push_back(c.label);
    return out;
  }
  std::vector<std::string> constraint_labels() const {
    std::vector<std::string> out;
    for (const auto& c : sim_.system().constraint_objects()) out.push_back(c.label);
    return out;
  }
  // The largest |C| over every row at the current state (System::
  // constraint_error); evaluating the constraints calls plugin code, so
  // without the GIL, as a force evaluation.
  double constraint_error() {
    py::gil_scoped_release release;
    return sys().constraint_error();
  }

  py::dict energies(double extra_dof) {
    // The constraint forces' virial needs the applied forces at this state
    // (pdyn/thermo.hpp), as the energy writer's frames evaluate them.
    if (sys().constraint_rows() > 0) evaluate_forces();
    const System& s = sim_.system();
    py::dict potential;
    const ParticleView p = s.view();
    for (const auto& f : s.force_objects()) {
      if (const auto u = f.force->potential_energy(p)) potential[py::str(f.label)] = *u;
    }
    py::dict out;
    out["kinetic"] = s.kinetic_energy();
    out["potential"] = potential;
    // Temperature and pressure as the energy writer's columns (pdyn/thermo.hpp);
    // the pressure is None in open space or when a force reports no virial.
    // With constraints: N_f less the independent rows, W with their forces'.
    const VirialSum w = total_virial(s, sim_.scene().solver.get(), sim_.scene().dt);
    const Thermo th = thermo(p, w.value, extra_dof + constraint_dof(s));
    out["dof"] = th.dof;
    out["kT"] = th.kT;
    out["temperature"] = th.temperature;
    out["pressure"] = std::isfinite(th.pressure) ? py::object(py::float_(th.pressure)) : py::none();
    out["reservoir"] = total_reservoir_energy(s, sim_.scene().solver.get());
    return out;
  }

  void set_masses(py::array_t<double, py::array::forcecast> m) {
    System& s = sys();
    if (m.ndim() != 1 || m.shape(0) != s.size()) {
      throw py::value_error(fmt::format("mass: expected {} masses (kg)", s.size()));
    }
    Eigen::VectorXd masses = Eigen::Map<const Eigen::VectorXd>(m.data(), s.size());
    for (Index i = 0; i < s.size(); ++i) {
      if (!(masses(i) > 0) || !std::isfinite(masses(i))) {
        throw py::value_error(
            fmt::format("mass[{}] = {} kg (expected a finite mass > 0)", i, masses(i)));
      }
    }
    // Same sizes: set_particles writes in place, so views stay valid.
    const Matrix3X x = s.positions(), v = s.velocities();
    auto radius = s.radii();
    auto type = s.types();
    auto images = s.images();
    const SystemAssembly assembly(s);
    assembly.set_particles(x, v, masses, s.fixed());
    assembly.set_radii(std::move(radius));
    assembly.set_types(std::move(type));
    assembly.set_images(std::move(images));
  }
  void set_fixed(Index i, bool on) {
    if (i < 0 || i >= sys().size()) {
      throw py::index_error(fmt::format("particle {} (expected 0 <= i < {})", i, sys().size()));
    }
    SystemAssembly(sys()).set_fixed(i, on);
  }
  void evaluate_forces() {
    if (sys().size() == 0) return;
    py::gil_scoped_release release;
    sys().compute_accelerations();
  }

 private:
  void forget(const std::string& label) {
    Scene& scene = sim_.scene();
    scene.libraries.erase(label);
    std::erase_if(scene.uses, [&](const PluginUse& u) { return u.label == label; });
  }

  struct Retired {
    std::unique_ptr<System> system;
    std::vector<py::weakref> views;
    bool alive() const {
      return std::any_of(views.begin(), views.end(),
                         [](const py::weakref& w) { return !w().is_none(); });
    }
  };

  CallLock lock_;
  std::shared_ptr<PluginRegistry> registry_;
  Simulation sim_;
  std::vector<py::weakref> views_;
  std::size_t live_ = 0;
  std::vector<Retired> retired_;
  int calls_ = 0;
};

std::unique_ptr<PySimulation> load(const std::string& source, bool is_text, const std::string& name,
                                   const std::vector<std::pair<std::string, std::string>>& set,
                                   const std::vector<std::filesystem::path>& plugin_path,
                                   int threads) {
  auto registry = make_registry(plugin_path);
  std::vector<Override> overrides;
  overrides.reserve(set.size());
  for (const auto& [path, value] : set) overrides.push_back({path, value});
  Scene scene = is_text ? load_scene_text(source, name, *registry, overrides)
                        : load_scene(source, *registry, overrides);
  return std::make_unique<PySimulation>(std::move(registry), std::move(scene), threads);
}

}  // namespace

namespace {

// A member function bound with the simulation's turn held (CallLock):
// `call` names it in the message of a refused re-entry.
template <class R, class... A>
auto entered(const char* call, R (PySimulation::*method)(A...)) {
  return [call, method](PySimulation& s, A... a) -> R {
    const auto turn = s.enter(call);
    return (s.*method)(std::forward<A>(a)...);
  };
}
template <class R, class... A>
auto entered(const char* call, R (PySimulation::*method)(A...) const) {
  return [call, method](PySimulation& s, A... a) -> R {
    const auto turn = s.enter(call);
    return (s.*method)(std::forward<A>(a)...);
  };
}
// A view of the store, made with the turn held (add_particles may be
// replacing the store on another thread).
template <py::array (PySimulation::*View)(py::handle)>
py::array entered_view(py::object self, const char* call) {
  auto& s = self.cast<PySimulation&>();
  const auto turn = s.enter(call);
  return (s.*View)(self);
}
// A property read with the turn held.
template <class Get>
auto entered_get(const char* call, Get get) {
  return [call, get](PySimulation& s) {
    const auto turn = s.enter(call);
    return get(s);
  };
}

}  // namespace

void bind_simulation(py::module_& m) {
  py::enum_<PluginKind>(m, "_Kind")
      .value("force", PluginKind::Force)
      .value("solver", PluginKind::Solver)
      .value("collider", PluginKind::Collider)
      .value("constraint", PluginKind::Constraint);
  py::class_<PySimulation>(m, "_Simulation")
      .def_property_readonly(
          "x", [](py::object self) { return entered_view<&PySimulation::positions>(self, "x"); })
      .def_property_readonly(
          "v", [](py::object self) { return entered_view<&PySimulation::velocities>(self, "v"); })
      .def_property_readonly(
          "mass", [](py::object self) { return entered_view<&PySimulation::masses>(self, "mass"); })
      .def_property_readonly(
          "f", [](py::object self) { return entered_view<&PySimulation::forces>(self, "f"); })
      .def_property_readonly(
          "fixed",
          [](py::object self) { return entered_view<&PySimulation::fixed>(self, "fixed"); })
      .def_property_readonly("n", entered_get("n", [](PySimulation& s) { return s.sys().size(); }))
      .def_property_readonly("t", entered_get("t", [](PySimulation& s) { return s.sys().time(); }))
      .def_property_readonly("steps",
                             entered_get("steps", [](PySimulation& s) { return s.sim().steps(); }))
      .def_property_readonly(
          "end_time",
          entered_get("end_time", [](PySimulation& s) { return s.sim().scene().end_time; }))
      .def_property_readonly(
          "scene_steps",
          entered_get("scene_steps", [](PySimulation& s) { return s.sim().scene().steps; }))
      .def_property_readonly(
          "file", entered_get("file", [](PySimulation& s) { return s.sim().scene().file; }))
      .def_property_readonly(
          "_warnings",
          entered_get("warnings", [](PySimulation& s) { return s.sim().scene().warnings; }))
      .def_property_readonly(
          "solver",
          entered_get("solver", [](PySimulation& s) { return s.sim().scene().solver_name; }))
      .def_property_readonly("force_evaluations", entered_get("force_evaluations",
                                                              [](PySimulation& s) {
                                                                return s.sys().force_evaluations();
                                                              }))
      .def_property("dt", entered_get("dt", [](PySimulation& s) { return s.sim().dt(); }),
                    [](PySimulation& s, double dt) {
                      const auto turn = s.enter("dt");
                      try {
                        s.sim().set_dt(dt);
                      } catch (const Error& e) {
                        throw py::value_error(e.what());
                      }
                    })
      .def("_labels", entered("forces", &PySimulation::labels))
      .def("_constraint_labels", entered("constraints", &PySimulation::constraint_labels))
      .def("constraint_error", entered("constraint_error", &PySimulation::constraint_error))
      .def("step", entered("step", &PySimulation::step), py::arg("n") = 1)
      .def("_run_until", entered("run", &PySimulation::run_until))
      .def("_run_to_end", entered("run", &PySimulation::run_to_end))
      .def("_add_plugin", entered("add", &PySimulation::add_plugin))
      .def("_add_python_force", entered("add_force", &PySimulation::add_python_force))
      .def("remove", entered("remove", &PySimulation::remove))
      .def("energies", entered("energies", &PySimulation::energies), py::arg("extra_dof") = 3.0)
      .def("_add_particles", entered("add_particles", &PySimulation::add_particles))
      .def("set_masses", entered("set_masses", &PySimulation::set_masses))
      .def("set_fixed", entered("set_fixed", &PySimulation::set_fixed))
      .def("evaluate_forces", entered("evaluate_forces", &PySimulation::evaluate_forces))
      .def("save_checkpoint",
           [](PySimulation& s, const std::filesystem::path& p) {
             const auto turn = s.enter("save");
             s.sim().save_checkpoint(p);
           })
      .def("restore_checkpoint", [](PySimulation& s, const std::filesystem::path& p, bool force) {
        const auto turn = s.enter("restore");
        s.sim().restore_checkpoint(p, force, "restore(path, force=True) restores anyway");
      });
  m.def("_load", &load);
}

}  // namespace pdyn::python
