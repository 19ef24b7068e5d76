// The viewer's simulation: real-time stepping, controls and interactions.
#include "session.hpp"

#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>

#include "pdyn/host/assembly.hpp"
#include "pdyn/host/resolve.hpp"
#include "pdyn/host/scene_drawables.hpp"
#include "pdyn/host/stepper.hpp"
#include "pdyn/targets.hpp"

namespace pdyn::viewer {

namespace fs = std::filesystem;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

namespace {

std::string read_scene_file(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) {
    throw SceneError(
        {{file.string(), "cannot read the scene file (expected a readable YAML file)"}});
  }
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string joined(const SceneError& e) {
  std::string s;
  for (const auto& d : e.diagnostics()) s += (s.empty() ? "" : "\n") + d.text();
  return s;
}

json vec(const Vec3& v) { return json::array({v.x(), v.y(), v.z()}); }

}  // namespace

Session::Session(SessionOptions options) : options_(std::move(options)) { load(true); }

Session::~Session() = default;

// (Re)loads the scene: from disk with a fresh scan of the plugin folders
// (`reload`), or from the text last loaded with the plugins already loaded
// (`reset`). Throws, leaving the running simulation as it was, if the scene
// does not load.
void Session::load(bool from_disk) {
  std::string text = from_disk ? read_scene_file(options_.scene) : text_;
  std::unique_ptr<PluginRegistry> registry;
  auto make_registry = [&] {
    registry = std::make_unique<PluginRegistry>();
    registry->discover(
        PluginRegistry::search_path(options_.plugin_path, DefaultFolders::LibraryAndProgram));
  };
  if (from_disk || !registry_) {
    make_registry();
  }
  const PluginRegistry& use = registry ? *registry : *registry_;
  Scene fresh = load_scene_text(text, options_.scene.string(), use, options_.overrides);
  if (registry && registry_) {
    // A rebuilt plugin: while the running scene's objects hold its library,
    // loading the same path again only returns the copy in memory. The new
    // scene loaded, so it is safe to let go of the old one and its plugins
    // and load once more, from the rebuilt files.
    bool rebuilt = false;
    for (const auto& [lib, time] : library_times_) {
      std::error_code ec;
      const auto now = fs::last_write_time(lib, ec);
      rebuilt = rebuilt || (!ec && now != time);
    }
    if (rebuilt) {
      fresh = Scene{};
      drags_.clear();
      scene_ = Scene{};
      registry_.reset();
      registry.reset();
      make_registry();
      try {
        fresh = load_scene_text(text, options_.scene.string(), *registry, options_.overrides);
      } catch (...) {
        // The rebuilt plugin refuses a scene its old build took: start over
        // from the text that last loaded, if it still does, and report.
        try {
          scene_ = load_scene_text(text_, options_.scene.string(), *registry, options_.overrides);
          obstacles_ = drawables(scene_);
          constraints_ = constraint_rows(scene_);
        } catch (...) {
          scene_ = Scene{};  // nothing loads: an empty system, no solver, until a reload works
          scene_.system = std::make_unique<System>();
          obstacles_ = {};
          constraints_ = {};
        }
        registry_ = std::move(registry);
        ++topology_;
        ++version_;
        throw;
      }
    }
  }
  // The colliders' shapes, asked once per load: a collider whose hook
  // fails refuses the load like a bad scene, and the running one is kept.
  Drawables obstacles = drawables(fresh);
  std::vector<ConstraintRows> constraints = constraint_rows(fresh);
  drags_.clear();
  scene_ = std::move(fresh);
  obstacles_ = std::move(obstacles);
  constraints_ = std::move(constraints);
  if (registry) registry_ = std::move(registry);
  text_ = std::move(text);
  library_times_.clear();
  for (const auto& [label, lib] : scene_.libraries) {
    std::error_code ec;
    const auto t = fs::last_write_time(lib, ec);
    if (!ec) library_times_[lib] = t;
  }
  dt_ = scene_.dt;
  debt_ = 0.0;
  steps_ = 0;
  message_.clear();
  attached_ = 0;
  rate_.clear();
  ++topology_;
  ++version_;
}

// Each constraint object's rows, for the page to draw. A pattern is fixed for
// the object's lifetime, so it is asked once per load, as the colliders'
// shapes are; one that throws, or that no longer names particles the
// system has (the kernel checked the first answer), refuses the load.
std::vector<Session::ConstraintRows> Session::constraint_rows(const Scene& scene) {
  std::vector<ConstraintRows> out;
  if (!scene.system) return out;
  const Index n = scene.system->size();
  for (const auto& entry : scene.system->constraint_objects()) {
    ConstraintRows c;
    c.label = entry.label;
    for (const auto& use : scene.uses) {
      if (use.kind == PluginKind::Constraint && use.label == entry.label) c.type = use.type;
    }
    try {
      c.pattern = entry.constraint->pattern();
    } catch (const std::exception& e) {
      throw PluginRuntimeError(entry.label, fmt::format("pattern() threw: {}", e.what()));
    } catch (...) {
      throw PluginRuntimeError(entry.label, "pattern() threw a non-standard exception");
    }
    const ConstraintPattern& p = c.pattern;
    bool ok = !p.row_begin.empty() && p.row_begin.front() == 0 && p.row_begin.back() == p.entries();
    for (std::size_t r = 1; ok && r < p.row_begin.size(); ++r)
      ok = p.row_begin[r - 1] <= p.row_begin[r];
    for (const Index k : p.particle) ok = ok && k >= 0 && k < n;
    if (!ok) {
      throw PluginRuntimeError(
          entry.label, fmt::format("pattern() gave the viewer a malformed pattern, or one naming a "
                                   "particle outside 0..{} (expected the one it gave the kernel)",
                                   n - 1));
    }
    out.push_back(std::move(c));
  }
  return out;
}

// ---------------------------------------------------------------------------
// Stepping

// One step of dt (an adaptive solver: one accepted step of at most dt), then
// the colliders' response, as the runner does. A plugin that throws, or a
// state that turns non-finite, stops the simulation on the last good state
// with a message for the page, instead of ending the server.
void Session::step_locked() {
  if (!scene_.solver) return;
  Stepper stepper(*scene_.system, *scene_.solver, scene_.solver_label);
  const double t0 = scene_.system->time();
  if (!stepper.step(dt_)) {
    const StepFault& f = stepper.fault();
    if (f.kind == StepFault::Kind::NonFiniteState) {
      fail(
          fmt::format("the state became non-finite at step {} (t = {:.6g} s) with {} and dt = "
                      "{:.3g} s; the last good state is kept (expected a smaller dt, or the "
                      "implicit_euler solver for stiff springs)",
                      steps_ + 1, t0, scene_.solver_name, dt_));
    } else {
      const std::string what =
          f.non_standard ? f.label + ": step threw a non-standard exception" : f.what;
      fail(fmt::format("{} at step {} (t = {:.6g} s); the last good state is kept", what,
                       steps_ + 1, t0));
    }
    return;
  }
  ++steps_;
  ++version_;
}

void Session::fail(std::string message) {
  playing_ = false;
  message_ = std::move(message);
  ++version_;
}

void Session::advance(double wall_seconds, double budget_seconds) {
  const std::lock_guard lock(mutex_);
  const auto start = Clock::now();
  if (playing_ && scene_.solver) {
    debt_ += speed_ * wall_seconds;
    const auto deadline = start + std::chrono::duration<double>(budget_seconds);
    const bool adaptive = scene_.solver->adaptive();
    // A fixed step is taken when at least (almost) a whole one is owed, so
    // that round-off in the wall clock does not skip or double steps.
    while (playing_ && debt_ >= (adaptive ? 1e-12 : dt_ * (1.0 - 1e-9))) {
      const double t0 = scene_.system->time();
      step_locked();
      debt_ -= scene_.system->time() - t0;
      if (Clock::now() >= deadline) {
        debt_ = std::min(debt_, dt_);  // behind real time: drop what cannot be caught up
        break;
      }
    }
  }
  rate_.emplace_back(start, scene_.system->time());
  while (rate_.size() > 2 && start - rate_.front().first > std::chrono::seconds(1)) {
    rate_.pop_front();
  }
}

// ---------------------------------------------------------------------------
// Commands

void Session::check_particle(const Command& c, const char* field, Index i) const {
  const Index n = scene_.system->size();
  if (i >= n) {
    throw CommandError(
        fmt::format("{}: field '{}' is {}, but there are {} particles (expected 0..{})", c.op_name,
                    field, i, n, n - 1));
  }
}

Params Session::defaults_of(const PluginRecord& r, const Params& given) const {
  Resolved resolved = resolve(r.descriptor->params, given);
  for (const auto& problem : resolved.problems) {
    if (problem.kind == ParamProblem::Kind::Missing) {
      throw CommandError(fmt::format(
          "{} needs the parameter '{}' (expected it chosen in the scene file, not in the viewer)",
          r.descriptor->name, problem.param));
    }
    throw CommandError(fmt::format("{}: {}", r.descriptor->name, problem.message));
  }
  return std::move(resolved.params);
}

std::shared_ptr<Force> Session::make_force(const char* type, const Params& params,
                                           const std::string& label) {
  const PluginRecord* r = registry_->find(PluginKind::Force, type);
  if (!r) {
    throw CommandError(
        fmt::format("this needs the '{}' force plugin, which was not found on the "
                    "plugin path (expected pdyn_force_{}.so)",
                    type, type));
  }
  const Params p = defaults_of(*r, params);
  const SceneContext ctx{scene_.system->view(), &scene_.groups};
  auto force = registry_->create_force(*r, p, ctx);
  scene_.libraries[label] = r->library;
  return force;
}

// A solver keeps what it learnt of the system between steps (verlet's last
// acceleration, rk45's step size, implicit_euler's matrix pattern). When an
// interaction changes the particles or the forces, a fresh one starts from
// the new system instead of trusting what no longer holds.
void Session::refresh_solver() {
  if (!scene_.solver) return;
  const PluginRecord* r = registry_->find(PluginKind::Solver, scene_.solver_name);
  if (!r) return;
  const SceneContext ctx{scene_.system->view(), &scene_.groups};
  scene_.solver = registry_->create_solver(*r, scene_.solver_params, ctx);
}

// Witkin's mouse spring is a damped spring from the particle to the cursor.
// Its default is stiff enough to move the whole scene's mass at a brisk
// 1.5 Hz (ks = M w^2), critically damped for the dragged particle
// (kd = 2 sqrt(ks m)), and both capped so that an explicit solver at the
// current dt stays stable for that particle: h sqrt(ks/m) <= 1 and
// h kd/m <= 1/2 (rk4 is stable to h w ~ 2.8).
std::pair<double, double> Session::default_mouse_spring(Index i) const {
  const System& sys = *scene_.system;
  double total = 0.0;
  for (Index k = 0; k < sys.size(); ++k) {
    if (!sys.fixed()[static_cast<std::size_t>(k)]) total += sys.masses()(k);
  }
  const double m = sys.masses()(i);
  const double w = 2.0 * std::numbers::pi * 1.5;
  const double ks = std::min(std::max(total, m) * w * w, m / (dt_ * dt_));
  const double kd = std::min(2.0 * std::sqrt(ks * m), 0.5 * m / dt_);
  return {ks, kd};
}

// `reload`: the scene file read again; on any problem the running
// simulation is kept and the client told why.
void Session::reload() {
  try {
    load(true);
  } catch (const SceneError& e) {
    throw CommandError("reload: the scene has errors; the running simulation is kept\n" +
                       joined(e));
  } catch (const std::exception& e) {
    throw CommandError(fmt::format("reload: {}; the running simulation is kept", e.what()));
  }
}

// `solver`: the named solver plugin with its defaults replaces the scene's.
void Session::choose_solver(const std::string& name) {
  System& sys = *scene_.system;
  const PluginRecord* r = registry_->find(PluginKind::Solver, name);
  if (!r) {
    std::string names;
    for (const auto& n : registry_->names(PluginKind::Solver))
      names += (names.empty() ? "" : ", ") + n;
    throw CommandError(fmt::format("solver: there is no solver plugin '{}' (expected one of: {})",
                                   name.size() > 40 ? name.substr(0, 40) + "..." : name, names));
  }
  Params p = defaults_of(*r, {});
  const SceneContext ctx{sys.view(), &scene_.groups};
  scene_.solver = registry_->create_solver(*r, p, ctx);
  scene_.solver_name = r->descriptor->name;
  scene_.solver_label = fmt::format("{} (chosen in the viewer)", scene_.solver_name);
  scene_.solver_params = std::move(p);
  scene_.libraries[scene_.solver_label] = r->library;
}

// `drag`: a mouse spring from the client's pointer to a particle (an anchor
// whose target the pointer moves), replacing the client's earlier one.
void Session::start_drag(const Command& c, int client) {
  System& sys = *scene_.system;
  check_particle(c, "id", *c.id);
  if (auto it = drags_.find(client); it != drags_.end()) {
    SystemAssembly(sys).remove_force(it->second.force.get());
    drags_.erase(it);
  }
  const auto [ks0, kd0] = default_mouse_spring(*c.id);
  Params p;
  p.set("ids", std::vector<Index>{*c.id});
  p.set("points", std::vector<Vec3>{*c.point});
  p.set("ks", c.ks.value_or(ks0));
  p.set("kd", c.kd.value_or(kd0));
  const std::string label = fmt::format("mouse spring (viewer client {})", client);
  auto force = make_force("anchor", p, label);
  if (!movable_targets(*force)) {
    throw CommandError(
        "drag: the 'anchor' plugin on the plugin path cannot move its target "
        "(expected it to implement pdyn::MovableTargets)");
  }
  SystemAssembly(sys).add_force(force, label);
  drags_[client] = {force, *c.id};
  refresh_solver();
}

// `attach`: a spring between two particles, at rest at their distance.
void Session::attach(const Command& c) {
  System& sys = *scene_.system;
  check_particle(c, "a", *c.a);
  check_particle(c, "b", *c.b);
  if (*c.a == *c.b) {
    throw CommandError(fmt::format(
        "attach: fields 'a' and 'b' are both particle {} (expected two different particles)",
        *c.a));
  }
  // Rest length = the current distance: the new spring starts at rest.
  const double rest = (sys.positions().col(*c.a) - sys.positions().col(*c.b)).norm();
  Params p;
  p.set("pairs", std::vector<IndexPair>{{*c.a, *c.b}});
  p.set("ks", std::vector<double>{c.ks.value_or(100.0)});
  p.set("kd", std::vector<double>{c.kd.value_or(0.1)});
  p.set("rest", std::vector<double>{rest});
  const std::string label = fmt::format("spring (attached in the viewer, #{})", ++attached_);
  auto force = make_force("spring", p, label);
  SystemAssembly(sys).add_force(force, label);
  scene_.uses.push_back({PluginKind::Force, "spring", label, std::move(p)});
  ++topology_;
  refresh_solver();
}

std::optional<Index> Session::apply(const Command& c, int client) {
  using Op = Command::Op;
  const std::lock_guard lock(mutex_);
  System& sys = *scene_.system;
  std::optional<Index> created;
  switch (c.op) {
    case Op::Play:
      if (!scene_.solver)
        throw CommandError("play: the scene has no solver (expected a loaded scene)");
      playing_ = true;
      message_.clear();
      debt_ = 0.0;
      break;
    case Op::Pause:
      playing_ = false;
      break;
    case Op::Step:
      message_.clear();
      step_locked();
      if (!message_.empty()) throw CommandError(message_);
      break;
    case Op::Reset:
      load(false);
      break;
    case Op::Reload:
      reload();
      break;
    case Op::Speed:
      if (*c.value > 1e6)
        throw CommandError("speed: field 'value' is too large (expected at most 1e6)");
      speed_ = *c.value;
      break;
    case Op::Dt:
      dt_ = *c.value;
      debt_ = 0.0;
      break;
    case Op::Solver:
      choose_solver(c.name);
      break;
    case Op::Drag:
      start_drag(c, client);
      break;
    case Op::Move:
      if (auto it = drags_.find(client); it != drags_.end()) {
        movable_targets(*it->second.force)->set_target(0, *c.point);
        sys.touch();  // the force changed: nothing evaluated before stays valid
      }
      break;
    case Op::Release:
      if (auto it = drags_.find(client); it != drags_.end()) {
        SystemAssembly(sys).remove_force(it->second.force.get());
        drags_.erase(it);
        refresh_solver();
      }
      break;
    case Op::Nail: {
      check_particle(c, "id", *c.id);
      const auto i = static_cast<std::size_t>(*c.id);
      SystemAssembly(sys).set_fixed(*c.id, sys.fixed()[i] == 0);
      ++topology_;
      refresh_solver();
      break;
    }
    case Op::Create:
      created = SystemAssembly(sys).add_particle(*c.point, Vec3::Zero(), *c.mass, false);
      ++topology_;
      refresh_solver();
      break;
    case Op::Attach:
      attach(c);
      break;
  }
  ++version_;
  return created;
}

void Session::forget_client(int client) {
  const std::lock_guard lock(mutex_);
  if (auto it = drags_.find(client); it != drags_.end()) {
    SystemAssembly(*scene_.system).remove_force(it->second.force.get());
    drags_.erase(it);
    refresh_solver();
    ++version_;
  }
}

// ---------------------------------------------------------------------------
// Observers

Frame Session::frame() const {
  const std::lock_guard lock(mutex_);
  const System& sys = *scene_.system;
  Frame f;
  f.topology = topology_;
  f.time = sys.time();
  f.step = steps_;
  f.playing = playing_;
  f.kinetic = sys.kinetic_energy();
  f.potential = sys.potential_energy();
  const Index n = sys.size();
  f.positions.resize(static_cast<std::size_t>(3 * n));
  f.speeds.resize(static_cast<std::size_t>(n));
  const auto x = sys.positions();
  const auto v = sys.velocities();
  for (Index i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k)
      f.positions[static_cast<std::size_t>(3 * i + k)] = static_cast<float>(x(k, i));
    f.speeds[static_cast<std::size_t>(i)] = static_cast<float>(v.col(i).norm());
  }
  return f;
}

std::uint64_t Session::version() const {
  const std::lock_guard lock(mutex_);
  return version_;
}
std::uint32_t Session::topology() const {
  const std::lock_guard lock(mutex_);
  return topology_;
}
bool Session::playing() const {
  const std::lock_guard lock(mutex_);
  return playing_;
}
std::uint64_t Session::steps() const {
  const std::lock_guard lock(mutex_);
  return steps_;
}
double Session::dt() const {
  const std::lock_guard lock(mutex_);
  return dt_;
}

std::string Session::scene_json() const {
  const std::lock_guard lock(mutex_);
  const System& sys = *scene_.system;
  const Index n = sys.size();
  json j{{"type", "scene"},
         {"version", kProtocolVersion},
         {"topology", topology_},
         {"file", options_.scene.string()},
         {"count", n}};
  json fixed = json::array();
  for (auto f : sys.fixed()) fixed.push_back(f ? 1 : 0);
  j["fixed"] = std::move(fixed);
  const Drawables& d = obstacles_;
  json links = json::array();
  for (const auto& l : scene_links(scene_)) links.push_back(json::array({l[0], l[1]}));
  j["links"] = std::move(links);
  // Each constraint object with its rows' particles: the page draws a row
  // over two particles as a rod, over one (a pin, a bead) as a ring on it.
  json constraints = json::array();
  for (const auto& c : constraints_) {
    const ConstraintPattern& p = c.pattern;
    json rows = json::array();
    for (Index r = 0; r < p.rows(); ++r) {
      json row = json::array();
      for (Index e = p.row_begin[static_cast<std::size_t>(r)];
           e < p.row_begin[static_cast<std::size_t>(r) + 1]; ++e) {
        row.push_back(p.particle[static_cast<std::size_t>(e)]);
      }
      rows.push_back(std::move(row));
    }
    constraints.push_back(json{{"type", c.type}, {"label", c.label}, {"rows", std::move(rows)}});
  }
  j["constraints"] = std::move(constraints);
  j["planes"] = json::array();
  for (const auto& p : d.planes)
    j["planes"].push_back({{"point", vec(p.point)}, {"normal", vec(p.normal)}});
  j["spheres"] = json::array();
  for (const auto& s : d.spheres)
    j["spheres"].push_back({{"center", vec(s.center)}, {"radius", s.radius}});
  j["boxes"] = json::array();
  for (const auto& b : d.boxes) j["boxes"].push_back({{"min", vec(b.min)}, {"max", vec(b.max)}});
  j["meshes"] = json::array();
  for (const auto& m : d.meshes) {
    json vertices = json::array(), triangles = json::array();
    for (const auto& v : m.vertices) vertices.push_back(vec(v));
    for (const auto& t : m.triangles) triangles.push_back(json::array({t[0], t[1], t[2]}));
    j["meshes"].push_back({{"vertices", std::move(vertices)}, {"triangles", std::move(triangles)}});
  }
  // Radii (m) when the scene gives any, else null: the page draws a
  // particle of radius > 0 as a sphere, any other as a point.
  j["radius"] = sys.radii().empty() ? json(nullptr) : json(sys.radii());
  j["box"] = nullptr;
  if (d.box) {
    j["box"] = {
        {"min", vec(d.box->min)},
        {"max", vec(d.box->max)},
        {"periodic", json::array({d.box->periodic[0], d.box->periodic[1], d.box->periodic[2]})}};
  }
  j["solvers"] = registry_->names(PluginKind::Solver);
  // A flat scene: every particle and its velocity lie in one coordinate
  // plane (the page then starts in its 2-D view along that axis).
  j["flat"] = nullptr;
  if (n > 0) {
    const auto x = sys.positions();
    const auto v = sys.velocities();
    const double extent = (x.rowwise().maxCoeff() - x.rowwise().minCoeff()).maxCoeff();
    constexpr const char* kPlane[3] = {"yz", "xz", "xy"};
    for (int k = 2; k >= 0; --k) {
      const double spread = x.row(k).maxCoeff() - x.row(k).minCoeff();
      if (spread <= 1e-9 * (1.0 + extent) && v.row(k).cwiseAbs().maxCoeff() == 0.0) {
        j["flat"] = kPlane[k];
        break;
      }
    }
  }
  return j.dump(-1, ' ', false, json::error_handler_t::replace);
}

std::string Session::status_json() const {
  const std::lock_guard lock(mutex_);
  double rtf = 0.0;
  if (rate_.size() >= 2) {
    const double wall =
        std::chrono::duration<double>(rate_.back().first - rate_.front().first).count();
    if (wall > 0) rtf = (rate_.back().second - rate_.front().second) / wall;
  }
  json j{{"type", "status"},
         {"playing", playing_},
         {"speed", speed_},
         {"solver", scene_.solver_name},
         {"dt", dt_},
         {"time", scene_.system->time()},
         {"step", steps_},
         {"rtf", rtf},
         {"count", scene_.system->size()}};
  j["message"] = message_.empty() ? json(nullptr) : json(message_);
  // max |C| over every constraint row (each row's unit: m for the shipped
  // ones), null without constraints. A constraint that throws here has
  // stopped the stepping too, and `message` says why; the status still goes.
  j["constraint_error"] = nullptr;
  if (scene_.system->constraint_rows() > 0) {
    try {
      j["constraint_error"] = scene_.system->constraint_error();
    } catch (const std::exception&) {
    }
  }
  return j.dump(-1, ' ', false, json::error_handler_t::replace);
}

std::string Session::state_json() const {
  const std::lock_guard lock(mutex_);
  const System& sys = *scene_.system;
  json particles = json::array();
  const auto x = sys.positions();
  const auto v = sys.velocities();
  for (Index i = 0; i < sys.size(); ++i) {
    particles.push_back({{"x", vec(x.col(i))},
                         {"v", vec(v.col(i))},
                         {"mass", sys.masses()(i)},
                         {"fixed", sys.fixed()[static_cast<std::size_t>(i)] != 0}});
  }
  json j{{"time", sys.time()},
         {"step", steps_},
         {"playing", playing_},
         {"solver", scene_.solver_name},
         {"dt", dt_},
         {"count", sys.size()},
         {"particles", std::move(particles)}};
  return j.dump(-1, ' ', false, json::error_handler_t::replace);
}

}  // namespace pdyn::viewer
