// The scene loader: YAML text -> validated, assembled Scene.
//
// The whole file is checked before anything is simulated, and every problem
// found is reported, each as `FILE:LINE:COLUMN: what is wrong (what was
// expected)`. Built-in sections (simulation, particles, grid, output) are
// described by the same ParamSpec lists that plugins use for their
// parameters, so one reader checks types, ranges, required and unknown keys
// everywhere.
//
// This file assembles a scene from its sections (simulation, particles,
// forces, colliders, output) and implements BuilderHost for the builders.
// The generic reader is yaml_reader.cpp, --set is overrides.cpp, the
// sections' specs are scene_specs.cpp, and the builders are
// scene_builders.cpp and grid_builder.cpp, the simulation box and the
// particles' radii and types scene_box.cpp, particles and boxes from files
// scene_files.cpp (all declared in loader.hpp and scene_builders.hpp).
#include <fmt/format.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>
#if defined(__GLIBC__)
#include <malloc.h>  // malloc_trim
#endif

#include "loader.hpp"
#include "pdyn/constraint_solver.hpp"
#include "pdyn/host/assembly.hpp"
#include "pdyn/host/runner.hpp"
#include "pdyn/host/side_files.hpp"
#include "pdyn/step_aware.hpp"
#include "pdyn/text.hpp"

namespace pdyn {

SceneError::SceneError(std::vector<Diagnostic> diagnostics)
    : Error([&] {
        std::string s;
        for (std::size_t i = 0; i < diagnostics.size(); ++i) {
          s += (i ? "\n" : "") + diagnostics[i].text();
        }
        return s;
      }()),
      diagnostics_(std::move(diagnostics)) {}

namespace loading {

// ---------------------------------------------------------------------------
// Sections

void Loader::read_simulation(const YAML::Node& n, Scene& scene) {
  if (!n.IsDefined()) {
    error(root_, "", "missing section 'simulation' (expected simulation: { dt: ..., steps: ... })");
    return;
  }
  if (!check_map(n, "simulation", "simulation: { dt: ..., steps: ..., solver: { type: ... } }")) {
    return;
  }
  auto p = read_params(n, "simulation", simulation_specs(),
                       {"solver", "box", "constraint_force", "neighbor"}, -1);
  if (n["box"].IsDefined() && !n["box"].IsNull()) read_box(n["box"]);
  if (n["neighbor"].IsDefined() && !n["neighbor"].IsNull()) read_neighbor(n["neighbor"], scene);
  if (n["constraint_force"].IsDefined() && !n["constraint_force"].IsNull()) {
    read_constraint_force(n["constraint_force"], scene);
  }
  if (p) {
    scene.dt = p->real("dt");
    if (p->has("threads")) scene.threads = static_cast<int>(p->integer("threads"));
    const bool has_steps = p->has("steps"), has_duration = p->has("duration");
    if (has_steps && has_duration) {
      // Point at the one a --set added, else at the one given last.
      auto from_set = [&](const char* key) {
        return where(n[key], fmt::format("simulation.{}", key)).rfind("--set ", 0) == 0;
      };
      auto mark = [&](const char* key) {
        const YAML::Mark m = n[key].Mark();
        return std::pair(m.line, m.column);
      };
      const bool at_steps =
          from_set("steps") || (!from_set("duration") && mark("steps") > mark("duration"));
      const char* key = at_steps ? "steps" : "duration";
      error(n[key], fmt::format("simulation.{}", key),
            fmt::format("simulation.{}: both 'steps' and 'duration' are given (expected one of "
                        "them)",
                        key));
    } else if (!has_steps && !has_duration) {
      error(n, "simulation",
            "simulation: neither 'steps' nor 'duration' is given (expected one of them, e.g. "
            "steps: 1000)");
    } else if (has_steps) {
      scene.steps = p->integer("steps");
      scene.end_time = static_cast<double>(scene.steps) * scene.dt;
    } else {
      // The last step is shortened so that the run ends exactly at `duration`.
      scene.end_time = p->real("duration");
      // Compared as a double: duration / dt may not fit an integer at all.
      const double steps = std::ceil(scene.end_time / scene.dt - 1e-9);
      if (!(steps <= static_cast<double>(static_cast<std::int64_t>(1) << 40))) {
        error(n["duration"], "simulation.duration",
              "simulation.duration: needs more than 2^40 steps (expected a duration / dt that a "
              "run can reach)");
      } else {
        scene.steps = static_cast<std::int64_t>(steps);
      }
    }
  }
}

// Witkin's feedback terms and the CG settings of the constraint force.
void Loader::read_constraint_force(const YAML::Node& n, Scene& scene) {
  const std::string path = "simulation.constraint_force";
  if (!check_map(n, path, "constraint_force: { ks: ..., kd: ..., tolerance: ... }")) return;
  auto p = read_params(n, path, constraint_force_specs(), {}, -1);
  if (!p) return;
  scene.constraint_feedback.ks = p->real("ks");
  scene.constraint_feedback.kd = p->real("kd");
  scene.constraint_feedback.tolerance = p->real("tolerance");
  scene.constraint_feedback.max_iterations = p->integer("max_iterations");
}

// LAMMPS's neigh_modify every / delay / check, to reproduce a LAMMPS run's
// rebuilds (and the pairs they miss) exactly.
void Loader::read_neighbor(const YAML::Node& n, Scene& scene) {
  const std::string path = "simulation.neighbor";
  if (!check_map(n, path, "neighbor: { every: N, delay: D, check: true }")) return;
  auto p = read_params(n, path, neighbor_specs(), {}, -1);
  if (!p) return;
  neighbor_node_ = n;
  scene.neighbor_schedule = {p->integer("every"), p->integer("delay"), p->boolean("check")};
  if (!scene.neighbor_schedule.check) {
    warnings_.push_back(fmt::format(
        "{}: simulation.neighbor.check: false rebuilds the neighbor lists only every {} "
        "steps whatever the particles do; pairs that come within the cutoff between "
        "rebuilds are missed (LAMMPS's neigh_modify check no: to reproduce a LAMMPS "
        "run)",
        where(n["check"], path + ".check"), scene.neighbor_schedule.every));
  }
}

void Loader::read_particles(const YAML::Node& n) {
  if (!n.IsDefined()) {
    error(root_, "",
          "missing section 'particles' (expected a list of particles or builders, "
          "e.g. - { position: [0, 0, 1], mass: 1 })");
    particles_ok_ = false;
    return;
  }
  if (!n.IsSequence()) {
    error(n, "particles", "particles: is not a list (expected a list of particles or builders)");
    particles_ok_ = false;
    return;
  }
  const std::size_t before = diags_.size();
  const auto specs = particle_specs();
  for (std::size_t i = 0; i < n.size(); ++i) {
    const YAML::Node item = n[i];
    const std::string path = fmt::format("particles[{}]", i);
    if (!check_map(item, path, "{ position: [x, y, z], mass: m } or a builder such as grid")) {
      continue;
    }
    const auto first = static_cast<Index>(x_.size());
    // Where a problem with one of this entry's particles is reported.
    auto made = [&](const YAML::Node& node, const std::string& at) {
      const auto end = static_cast<Index>(x_.size());
      if (end > first) entries_.push_back({first, end, node, at});
    };
    if (item["file"].IsDefined()) {  // a side file or another program's (scene_files.cpp)
      read_particle_file(item, path);
      made(item["file"], path + ".file");
      continue;
    }
    const auto& builders = builder_names();
    const auto builder = std::find_if(builders.begin(), builders.end(),
                                      [&](const std::string& b) { return item[b].IsDefined(); });
    if (builder != builders.end()) {
      if (item.size() != 1) {
        error(item, path,
              fmt::format("{}: a builder entry holds only its builder (expected "
                          "{{ {}: {{ ... }} }})",
                          path, *builder));
        continue;
      }
      read_builder(*this, *builder, item[*builder], path + "." + *builder);
      made(item[*builder], path + "." + *builder);
      continue;
    }
    if (item["grid"].IsDefined()) {
      if (item.size() != 1) {
        error(item, path,
              fmt::format("{}: a builder entry holds only its builder (expected "
                          "{{ grid: {{ ... }} }})",
                          path));
        continue;
      }
      read_grid(*this, item["grid"], path + ".grid");
      made(item["grid"], path + ".grid");
      continue;
    }
    auto p = read_params(item, path, specs, {}, -1);
    if (!p) continue;
    x_.push_back(p->vec3("position"));
    v_.push_back(p->vec3("velocity"));
    m_.push_back(p->real("mass"));
    fixed_.push_back(p->boolean("fixed") ? 1 : 0);
    set_properties(first, 1, particle_properties(*p, ""));
    made(item["position"], path + ".position");
  }
  if (diags_.size() != before) particles_ok_ = false;
  if (particles_ok_ && x_.empty()) {
    error(n, "particles",
          "particles: the scene has no particles (expected at least one "
          "particle or builder)");
    particles_ok_ = false;
  }
}

// ---------------------------------------------------------------------------
// BuilderHost

bool Loader::can_add(std::int64_t count, const YAML::Node& at, const std::string& path) {
  if (count <= kMaxParticles && static_cast<std::int64_t>(x_.size()) + count <= kMaxParticles) {
    return true;
  }
  error(at, path,
        fmt::format("{}: {} particles is too many (expected at most {} particles in a "
                    "scene)",
                    path, count, kMaxParticles));
  return false;
}

void Loader::add_group(const std::string& name, std::vector<Index> members, const YAML::Node& at,
                       const std::string& path) {
  if (!groups_.emplace(name, std::move(members)).second) {
    error(at, path,
          fmt::format("{}: group '{}' is already defined (expected a unique name)", path, name));
  }
}

// A builder's force or constraint objects (springs, rods): the plugin, and
// the keys of `node` checked against its parameters less the `generated`
// lists. Nothing if the plugin is missing or a key is wrong (reported).
std::optional<PendingPlugin> Loader::builder_plugin(PluginKind kind, const std::string& plugin,
                                                    const YAML::Node& node, const std::string& path,
                                                    const Params& generated) {
  registry_.require_healthy(plugin);
  const PluginRecord* rec = registry_.find(kind, plugin);
  if (!rec) {
    error(node, path,
          fmt::format("{}: needs the '{}' {} plugin, which was not found (expected it on the "
                      "plugin path)",
                      path, plugin, kind_name(kind)));
    return std::nullopt;
  }
  std::vector<std::string> names;
  for (const auto& kv : generated.values()) names.push_back(kv.first);
  // A family left out entirely has no keys to check.
  const YAML::Node keys = node.IsDefined() && node.IsMap() ? node : YAML::Node(YAML::NodeType::Map);
  auto params = read_plugin_params(keys, path, *rec, names);
  const auto compliance =
      kind == PluginKind::Constraint ? read_compliance(keys, path) : std::optional<double>(0.0);
  if (!params || !compliance) return std::nullopt;
  for (const auto& [key, value] : generated.values()) params->set(key, value);
  return PendingPlugin{rec, std::move(*params), keys, path, *compliance};
}

void Loader::add_force(const std::string& plugin, const YAML::Node& node, const std::string& path,
                       const Params& generated, const Params& defaults, bool create) {
  auto p = builder_plugin(PluginKind::Force, plugin, node, path, generated);
  if (!p || !create) return;
  for (const auto& [key, value] : defaults.values()) {
    if (!p->node[key].IsDefined() || p->node[key].IsNull()) p->params.set(key, value);
  }
  builder_forces_.push_back(std::move(*p));
}

void Loader::add_constraint(const std::string& plugin, const YAML::Node& node,
                            const std::string& path, const Params& generated, bool create) {
  auto p = builder_plugin(PluginKind::Constraint, plugin, node, path, generated);
  if (p && create) builder_constraints_.push_back(std::move(*p));
}

const PluginRecord* Loader::find_plugin(const YAML::Node& item, const std::string& path,
                                        PluginKind kind) {
  const YAML::Node t = item["type"];
  const char* kname = kind_name(kind);
  if (!t.IsDefined() || t.IsNull()) {
    error(item, path,
          fmt::format("{}: missing key 'type' (expected the name of a {} plugin: {})", path, kname,
                      join(registry_.names(kind))));
    return nullptr;
  }
  if (!t.IsScalar() || !is_valid_plugin_name(t.Scalar())) {
    error(t, path + ".type",
          fmt::format("{}.type: '{}' is not a plugin name (expected [a-z0-9_]+, one of: {})", path,
                      shown(t), join(registry_.names(kind))));
    return nullptr;
  }
  const std::string& name = t.Scalar();
  if (const PluginRecord* r = registry_.find(kind, name)) {
    registry_.require_healthy(name);
    return r;
  }
  registry_.require_healthy(name);  // a library for it exists but is broken: exit 3
  if (const PluginRecord* other = registry_.find_any(name)) {
    error(t, path + ".type",
          fmt::format("{}.type: '{}' is a {} plugin, not a {} (expected one of: {})", path, name,
                      kind_name(other->descriptor->kind), kname, join(registry_.names(kind))));
    return nullptr;
  }
  const auto names = registry_.names(kind);
  const std::string guess = closest_match(name, names);
  error(t, path + ".type",
        fmt::format("{}.type: unknown {} type '{}' ({}expected one of: {})", path, kname, name,
                    guess.empty() ? "" : fmt::format("did you mean '{}'? ", guess),
                    names.empty() ? "none found on the plugin path" : join(names)));
  return nullptr;
}

std::optional<Params> Loader::read_plugin_params(const YAML::Node& item, const std::string& path,
                                                 const PluginRecord& rec,
                                                 const std::vector<std::string>& generated) {
  std::vector<ParamSpec> specs;
  for (const auto& s : rec.descriptor->params) {
    if (std::find(generated.begin(), generated.end(), s.name) == generated.end()) {
      specs.push_back(s);
    }
  }
  const Index n = particles_ok_ ? static_cast<Index>(x_.size()) : -1;
  const bool is_builder = !generated.empty();
  std::vector<std::string> host_keys;
  if (!is_builder) host_keys.push_back("type");
  if (rec.descriptor->kind == PluginKind::Constraint) host_keys.push_back("compliance");
  return read_params(item, path, specs, host_keys, n);
}

// Compliance belongs to every constraint, a third party's too, so the host
// reads it rather than each plugin: alpha in XPBD's C + alpha lambda = 0
// (Macklin, Muller & Chentanez 2016, eq. 4), in the row's unit per newton.
std::optional<double> Loader::read_compliance(const YAML::Node& item, const std::string& path) {
  const YAML::Node c = item["compliance"];
  if (!c.IsDefined() || c.IsNull()) return 0.0;
  static const ParamSpec spec = param::real("compliance", 0.0, "unit/N",
                                            "the row's unit per newton (m/N for a rod); 0 = rigid")
                                    .at_least(0.0);
  const auto v = read_value(c, path + ".compliance", spec, -1);
  if (!v) return std::nullopt;
  const double alpha = std::get<double>(*v);
  if (!(alpha >= 0.0) || !std::isfinite(alpha)) {
    error(c, path + ".compliance",
          fmt::format("{}.compliance: {} is not a compliance (expected a finite number >= 0, "
                      "in the row's unit per newton; 0 = rigid)",
                      path, c.Scalar()));
    return std::nullopt;
  }
  return alpha;
}

void Loader::read_plugin_list(const YAML::Node& n, const char* section, PluginKind kind,
                              std::vector<PendingPlugin>& out) {
  if (!n.IsDefined() || n.IsNull()) return;
  if (!n.IsSequence()) {
    error(n, section,
          fmt::format("{}: is not a list (expected a list of {{ type: NAME, ... }})", section));
    return;
  }
  for (std::size_t i = 0; i < n.size(); ++i) {
    const YAML::Node item = n[i];
    const std::string path = fmt::format("{}[{}]", section, i);
    if (!check_plugin_map(item, path, kind)) continue;
    const PluginRecord* rec = find_plugin(item, path, kind);
    if (!rec) continue;
    auto params = read_plugin_params(item, path, *rec, {});
    const auto compliance =
        kind == PluginKind::Constraint ? read_compliance(item, path) : std::optional<double>(0.0);
    if (params && compliance) out.push_back({rec, std::move(*params), item, path, *compliance});
  }
}

// A file name, not a folder, in a place this user can write: found now
// rather than after the whole run.
bool Loader::output_file_name(const YAML::Node& at, const std::string& key_path,
                              const std::string& v) {
  std::error_code ec;
  if (v.empty() || v.back() == '/' || fs::is_directory(v, ec)) {
    error(at, key_path,
          fmt::format("{}: '{}' is a folder, not a file (expected a file name, "
                      "e.g. out/run.csv)",
                      key_path, v));
    return false;
  }
  // The nearest folder that exists must be writable: the run creates the
  // rest. (A file on the way is reported by check_written_files.)
  for (fs::path dir = fs::absolute(v, ec).parent_path(); !dir.empty(); dir = dir.parent_path()) {
    if (fs::is_directory(dir, ec)) {
      if (::access(dir.c_str(), W_OK) != 0) {
        error(at, key_path,
              fmt::format("{}: cannot write '{}': the folder '{}' is not writable ({}) (expected "
                          "a folder this user can write)",
                          key_path, v, dir.string(), std::strerror(errno)));
        return false;
      }
      break;
    }
    if (dir == dir.root_path()) break;
  }
  return true;
}

// The checkpoint keys: output.checkpoint (mapping form) or checkpoint (top
// level, any form).
void Loader::read_checkpoint(const YAML::Node& c, const std::string& path, Scene& scene) {
  if (!c.IsDefined() || c.IsNull()) return;
  if (!check_map(c, path, "checkpoint: { path: FILE.ckpt, every: N }")) return;
  if (auto cp = read_params(c, path, checkpoint_specs(), {}, -1)) {
    if (output_file_name(c["path"], path + ".path", cp->string("path"))) {
      scene.output.checkpoint = cp->string("path");
      checkpoint_node_ = c["path"];
      checkpoint_key_ = path + ".path";
    }
    scene.output.checkpoint_every = cp->integer("every");
  }
}

// A writer the mapping form implies (csv for `path`, energy for `energy`),
// with its plugin's defaults and `params` over them.
void Loader::implied_writer(const YAML::Node& at, const std::string& key_path,
                            const std::string& plugin, const std::string& file, std::int64_t every,
                            const Params& params, Scene& scene) {
  registry_.require_healthy(plugin);
  const PluginRecord* rec = registry_.find(PluginKind::Writer, plugin);
  if (!rec) {
    error(at, key_path,
          fmt::format("{}: needs the '{}' writer plugin, which was not found (expected it on the "
                      "plugin path)",
                      key_path, plugin));
    return;
  }
  const Resolved r = resolve(rec->descriptor->params, params);
  for (const auto& problem : r.problems) {
    error(at, key_path, fmt::format("{}: the '{}' writer: {}", key_path, plugin, problem.message));
  }
  WriterSpec w{*rec,  fmt::format("{} ({})", plugin, where(at, key_path)), file,
               every, rec->descriptor->writer_traits.default_fields,       r.params};
  scene.output.writers.push_back(std::move(w));
  writer_nodes_.push_back({at, key_path});
}

void Loader::read_output(const YAML::Node& n, const YAML::Node& top_checkpoint, Scene& scene) {
  if (n.IsDefined() && n.IsSequence()) {
    read_writer_list(n, scene);
  } else if (n.IsDefined() && !n.IsNull() &&
             check_map(n, "output",
                       "output: a list of writers, e.g. - { type: csv, path: FILE.csv, every: N }, "
                       "or { path: FILE.csv, every: N, energy: FILE.csv }")) {
    read_output_map(n, scene);
  }
  if (top_checkpoint.IsDefined() && !top_checkpoint.IsNull()) {
    if (!scene.output.checkpoint.empty()) {
      error(top_checkpoint, "checkpoint",
            fmt::format("checkpoint: the checkpoint is also given as {} (expected one of them)",
                        checkpoint_key_));
    } else {
      read_checkpoint(top_checkpoint, "checkpoint", scene);
    }
  }
  check_written_files(scene);
}

// Today's single mapping: one csv writer and one energy writer.
void Loader::read_output_map(const YAML::Node& n, Scene& scene) {
  auto p = read_params(n, "output", output_specs(), {"checkpoint"}, -1);
  if (!p) return;
  read_checkpoint(n["checkpoint"], "output.checkpoint", scene);
  const std::int64_t every = p->integer("every");
  scene.output.every = every;
  if (p->has("path") && output_file_name(n["path"], "output.path", p->string("path"))) {
    Params csv;
    csv.set("unwrapped", p->boolean("unwrapped"));
    implied_writer(n["path"], "output.path", "csv", p->string("path"), every, csv, scene);
    if (!scene.output.writers.empty()) {
      beside_ = scene.output.writers.size() - 1;
      scene.output.checkpoint_beside = p->string("path");
    }
  }
  if (p->has("energy") && output_file_name(n["energy"], "output.energy", p->string("energy"))) {
    implied_writer(n["energy"], "output.energy", "energy", p->string("energy"), every, Params{},
                   scene);
  }
}

// `output: [ { type: NAME, path: FILE, every: N, fields: [...], params... } ]`
void Loader::read_writer_list(const YAML::Node& n, Scene& scene) {
  const auto common = writer_entry_keys();
  for (std::size_t i = 0; i < n.size(); ++i) {
    const YAML::Node item = n[i];
    const std::string path = fmt::format("output[{}]", i);
    if (!check_plugin_map(item, path, PluginKind::Writer)) continue;
    const PluginRecord* rec = find_plugin(item, path, PluginKind::Writer);
    if (!rec) continue;
    std::vector<ParamSpec> specs = common;
    for (const auto& s : rec->descriptor->params) specs.push_back(s);
    auto all = read_params(item, path, specs, {"type"}, -1);
    if (!all) continue;
    WriterSpec w{*rec,
                 fmt::format("{} ({})", rec->descriptor->name, where(item, path)),
                 all->string("path"),
                 all->integer("every"),
                 rec->descriptor->writer_traits.default_fields,
                 Params{}};
    for (const auto& s : rec->descriptor->params) {
      if (all->has(s.name)) w.params.set(s.name, all->values().find(s.name)->second);
    }
    bool ok = output_file_name(item["path"], path + ".path", all->string("path"));
    if (all->has("fields")) {
      const auto& allowed = rec->descriptor->writer_traits.fields;
      const auto& asked = all->strings("fields");
      for (std::size_t k = 0; k < asked.size(); ++k) {
        if (std::find(allowed.begin(), allowed.end(), asked[k]) != allowed.end()) continue;
        const std::string at = fmt::format("{}.fields[{}]", path, k);
        const bool known = std::find(known_fields().begin(), known_fields().end(), asked[k]) !=
                           known_fields().end();
        error(item["fields"][k], at,
              fmt::format("{}: {} field '{}' for the '{}' writer (expected {})", at,
                          known ? "unsupported" : "unknown", asked[k], rec->descriptor->name,
                          allowed.empty() ? std::string("no fields: its columns are fixed")
                                          : "one of: " + join(allowed)));
        ok = false;
      }
      w.fields = asked;
    }
    if (!ok) continue;
    if (scene.output.writers.empty()) {
      beside_ = 0;
      scene.output.checkpoint_beside = w.path;
    }
    scene.output.writers.push_back(std::move(w));
    writer_nodes_.push_back({item["path"], path + ".path"});
  }
}

// Every file the run may write (written_paths.hpp), including the checkpoint
// an interrupted run writes when the scene names none, against each other,
// the scene file and the side files read so far.
void Loader::check_written_files(const Scene& scene) {
  std::vector<NamedPath> written;
  auto add = [&](const YAML::Node& at, const std::string& key, const fs::path& file,
                 bool beside_output = false) {
    if (!file.empty()) written.push_back({key, where(at, key), file, beside_output});
  };
  for (std::size_t k = 0; k < scene.output.writers.size(); ++k) {
    add(writer_nodes_[k].first, writer_nodes_[k].second, scene.output.writers[k].path);
  }
  if (!scene.output.checkpoint.empty()) {
    add(checkpoint_node_, checkpoint_key_, scene.output.checkpoint);
  } else if (!scene.output.checkpoint_beside.empty()) {
    // Written only on an interrupt or a plugin fault: named so that the
    // user sees why, and how to choose another.
    const auto& [node, first] = writer_nodes_[beside_];
    add(node,
        first == "output.path"
            ? "the checkpoint of an interrupted run (output.path with .ckpt; set "
              "output.checkpoint.path to choose)"
            : fmt::format("the checkpoint of an interrupted run ({} with .ckpt; set "
                          "checkpoint.path to choose)",
                          first),
        checkpoint_path(scene), /*beside_output=*/true);
  }
  std::vector<NamedPath> read = read_files_;
  std::error_code ec;
  if (fs::is_regular_file(file_, ec)) read.push_back({"the scene file", "", file_});
  for (auto& d : check_written_paths(written, read)) diags_.push_back(std::move(d));
}

template <class Create>
auto Loader::create(const PendingPlugin& p, Create&& create_fn) -> decltype(create_fn()) {
  try {
    return create_fn();
  } catch (const ParamError& e) {
    YAML::Node at = p.node[e.param()];
    std::string path = p.path + "." + e.param();
    if (at.IsDefined() && e.element() >= 0 && at.IsSequence() &&
        static_cast<std::size_t>(e.element()) < at.size()) {
      at.reset(at[e.element()]);
      path += fmt::format("[{}]", e.element());
    }
    error(at.IsDefined() ? at : p.node, path, fmt::format("{}: {}", path, e.what()));
  } catch (const PluginError&) {
    throw;
  } catch (const std::exception& e) {
    error(p.node, p.path,
          fmt::format("{}: plugin '{}' ({}) refused its parameters: {}", p.path,
                      p.record->descriptor->name, p.record->library.string(), e.what()));
  }
  return nullptr;
}

// The scene's text as YAML: a mapping, or located problems.
YAML::Node Loader::parse(const std::string& text) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    if (const auto b = unclosed_flow(text, e.mark)) {
      const char close = b->bracket == '{' ? '}' : ']';
      diags_.push_back({fmt::format("{}:{}:{}", file_, b->line + 1, b->column + 1),
                        fmt::format("malformed YAML: this '{}' is never closed (expected a '{}' "
                                    "closing it; the parser stopped at line {}, column {}: {})",
                                    b->bracket, close, e.mark.line + 1, e.mark.column + 1, e.msg)});
    } else {
      diags_.push_back({fmt::format("{}:{}:{}", file_, e.mark.line + 1, e.mark.column + 1),
                        fmt::format("malformed YAML: {} ({})", e.msg, yaml_hint(text, e))});
    }
    fail();
  } catch (const YAML::Exception& e) {
    diags_.push_back({file_, fmt::format("malformed YAML: {} (expected valid YAML)", e.msg)});
    fail();
  }
  if (!root.IsDefined() || root.IsNull()) {
    diags_.push_back({file_ + ":1:1",
                      "the scene is empty (expected the sections simulation, "
                      "particles, and optionally velocities, output, forces, colliders)"});
    fail();
  }
  if (!root.IsMap()) {
    error(root, "",
          "the scene is not a mapping (expected the sections simulation, particles, "
          "and optionally velocities, output, forces, colliders)");
    fail();
  }
  return root;
}

namespace {

// Compliance (XPBD's alpha) is honoured only by a solver that says so
// (pdyn/constraint_solver.hpp); the others treat every constraint as rigid,
// which would silently drop it.
bool enforces_constraints(const Solver& solver) {
  const auto* cs = dynamic_cast<const ConstraintSolver*>(&solver);
  return cs != nullptr && cs->enforces_constraints();
}

bool honours_compliance(const Solver& solver) {
  const auto* cs = dynamic_cast<const ConstraintSolver*>(&solver);
  return cs != nullptr && cs->enforces_constraints() && cs->honours_compliance();
}

std::string compliance_conflict(const std::string& solver) {
  return fmt::format(
      "is a compliant constraint, which solver '{}' treats as rigid (expected compliance 0, "
      "or a solver that honours it, e.g. solver: {{ type: xpbd }})",
      solver);
}

// What a checkpoint must match: the scene after overrides, less the run
// length, which a resumed run may extend, and the thread count.
std::string canonical_text(const YAML::Node& root) {
  YAML::Node canonical = YAML::Clone(root);
  if (canonical["simulation"].IsMap()) {
    canonical["simulation"].remove("steps");
    canonical["simulation"].remove("duration");
    canonical["simulation"].remove("threads");  // bit-identical results for any count
  }
  YAML::Emitter emitter;
  emitter << canonical;
  return emitter.c_str();
}

}  // namespace

// simulation.solver, or the default rk4 with its defaults.
void Loader::read_solver(const YAML::Node& root, std::vector<PendingPlugin>& solvers) {
  const YAML::Node sim = root["simulation"];
  if (sim.IsMap() && sim["solver"].IsDefined() && !sim["solver"].IsNull()) {
    const YAML::Node s = sim["solver"];
    if (check_plugin_map(s, "simulation.solver", PluginKind::Solver)) {
      if (const PluginRecord* rec = find_plugin(s, "simulation.solver", PluginKind::Solver)) {
        if (auto params = read_plugin_params(s, "simulation.solver", *rec, {})) {
          solvers.push_back({rec, std::move(*params), s, "simulation.solver"});
        }
      }
    }
  } else {
    registry_.require_healthy("rk4");
    if (const PluginRecord* rec = registry_.find(PluginKind::Solver, "rk4")) {
      // The defaults: a solver that requires a parameter is refused like a
      // `solver: { type: rk4 }` without it.
      const Resolved defaults = resolve(rec->descriptor->params, Params{});
      for (const auto& problem : defaults.problems) {
        error(sim.IsDefined() ? sim : root, "simulation",
              fmt::format("simulation: the default solver 'rk4': {}", problem.message));
      }
      solvers.push_back({rec, defaults.params, sim, "simulation"});
    } else {
      error(sim.IsDefined() ? sim : root, "simulation",
            "simulation: no solver is given and the default 'rk4' was not found (expected "
            "simulation.solver: { type: NAME })");
    }
  }
}

namespace {

// Why `force` cannot run with `solver`, or "": a force held over each fixed
// step (pdyn/step_aware.hpp) scales with the step's length, which an
// adaptive solver chooses itself. One message for a scene and for a force
// or solver added to a running simulation.
std::string fixed_step_conflict(const Force& force, const std::string& force_name,
                                const Solver& solver, const std::string& solver_name) {
  if (!solver.adaptive() || dynamic_cast<const StepAware*>(&force) == nullptr) return {};
  return fmt::format(
      "{} draws a force held over each fixed step; {} chooses its own step "
      "lengths (expected a fixed-step solver: verlet, rk4, euler, ...)",
      force_name, solver_name);
}

}  // namespace

// The System with the particles, the box, radii, types and image counts the
// sections read: before any force or collider exists, so that their
// factories see all of it in SceneContext::particles.
void Loader::assemble_system(Scene& scene) {
  const Index n = static_cast<Index>(x_.size());
  Matrix3X x(3, n), v(3, n);
  Eigen::VectorXd m(n);
  for (Index i = 0; i < n; ++i) {
    // Along periodic axes a particle starts inside the box, with no
    // images: wrap() leaves a position already inside it bit for bit.
    x.col(i) = box_ ? box_->wrap(x_[i]) : x_[i];
    v.col(i) = v_[i];
    m(i) = m_[i];
  }
  apply_velocities(v, m);
  scene.system = std::make_unique<System>();
  const SystemAssembly assembly(*scene.system);
  assembly.set_particles(x, v, m, fixed_);
  if (!images_.empty()) {  // a LAMMPS file's image flags (scene_files.cpp)
    images_.resize(static_cast<std::size_t>(n), {0, 0, 0});
    assembly.set_images(std::move(images_));
  }
  // Before any force or collider exists: their factories see the box, the
  // radii and the types in SceneContext::particles.
  if (box_) assembly.set_domain(*box_);
  if (!radius_.empty()) {
    radius_.resize(static_cast<std::size_t>(n), 0.0);
    assembly.set_radii(std::move(radius_));
  }
  if (!type_.empty()) {
    type_.resize(static_cast<std::size_t>(n), 0);
    assembly.set_types(std::move(type_));
  }
}

// The plugin objects, created in scene order and added to the System; each
// object's parameters move into scene.uses once it exists (no copy of a
// large spring list).
void Loader::create_plugins(Scene& scene, std::vector<PendingPlugin>& forces,
                            std::vector<PendingPlugin>& colliders,
                            std::vector<PendingPlugin>& constraints,
                            const std::vector<PendingPlugin>& solvers) {
  scene.groups = groups_;
  const SceneContext ctx{scene.system->view(), &scene.groups};
  const SystemAssembly assembly(*scene.system);
  auto label = [&](const PendingPlugin& p) {
    return fmt::format("{} ({})", p.record->descriptor->name, where(p.node, p.path));
  };
  // Each object's parameters move into scene.uses once it exists: no copy
  // of a large spring list.
  auto keep = [&](PendingPlugin& p, PluginKind kind) {
    scene.uses.push_back({kind, p.record->descriptor->name, label(p), std::move(p.params)});
  };
  std::vector<std::pair<const PendingPlugin*, const Force*>> created;  // checked with the solver
  for (auto* list : {&builder_forces_, &forces}) {
    for (auto& p : *list) {
      auto f = create(p, [&] { return registry_.create_force(*p.record, p.params, ctx); });
      if (!f) continue;
      created.emplace_back(&p, f.get());
      assembly.add_force(std::move(f), label(p));
      scene.libraries[label(p)] = p.record->library;
      scene.force_traits[label(p)] = p.record->descriptor->force_traits;
      keep(p, PluginKind::Force);
    }
  }
  for (auto& p : colliders) {
    auto c = create(p, [&] { return registry_.create_collider(*p.record, p.params, ctx); });
    if (!c) continue;
    assembly.add_collider(std::move(c), label(p));
    scene.libraries[label(p)] = p.record->library;
    keep(p, PluginKind::Collider);
  }
  assembly.set_constraint_feedback(scene.constraint_feedback);
  // The builders' rods first, as their springs come before the forces.
  constraints.insert(constraints.begin(), std::make_move_iterator(builder_constraints_.begin()),
                     std::make_move_iterator(builder_constraints_.end()));
  builder_constraints_.clear();
  for (auto& p : constraints) {
    auto c = create(p, [&] { return registry_.create_constraint(*p.record, p.params, ctx); });
    if (!c) continue;
    try {
      assembly.add_constraint(std::move(c), label(p), p.compliance);
    } catch (const Error& e) {  // a pattern naming a particle the scene does not have
      error(p.node, p.path, fmt::format("{}: {}", p.path, e.what()));
      continue;
    }
    scene.libraries[label(p)] = p.record->library;
    keep(p, PluginKind::Constraint);
  }
  for (const auto& p : solvers) {
    scene.solver = create(p, [&] { return registry_.create_solver(*p.record, p.params, ctx); });
    scene.solver_name = p.record->descriptor->name;
    scene.solver_label = label(p);
    scene.solver_params = p.params;
    scene.libraries[label(p)] = p.record->library;
  }
  if (scene.solver) assembly.enable_constraint_force(!enforces_constraints(*scene.solver));
  if (scene.solver && !honours_compliance(*scene.solver)) {
    for (const auto& p : constraints) {
      if (p.compliance > 0.0) {
        error(p.node["compliance"], p.path + ".compliance",
              fmt::format("{}.compliance: {} {}", p.path, p.compliance,
                          compliance_conflict(scene.solver_name)));
      }
    }
  }
  for (const auto& [p, force] : created) {
    const std::string why = scene.solver ? fixed_step_conflict(*force, p->record->descriptor->name,
                                                               *scene.solver, scene.solver_name)
                                         : std::string();
    if (!why.empty()) error(p->node, p->path, fmt::format("{}: {}", p->path, why));
  }
  for (const auto& w : scene.output.writers) scene.libraries[w.label] = w.record.library;
}

Scene Loader::load(const std::string& text) {
  Scene scene;
  scene.file = file_;
  YAML::Node root = parse(text);
  apply_overrides(root);
  if (!diags_.empty()) fail();
  root_.reset(root);
  scene.canonical_text = canonical_text(root);

  check_keys(root, "",
             {"simulation", "output", "checkpoint", "particles", "velocities", "forces",
              "colliders", "constraints", "special_bonds"});
  read_simulation(root["simulation"], scene);
  read_particles(root["particles"]);
  check_inside_box();
  read_velocities(root["velocities"]);
  std::vector<PendingPlugin> forces, colliders, constraints, solvers;
  read_plugin_list(root["forces"], "forces", PluginKind::Force, forces);
  read_plugin_list(root["colliders"], "colliders", PluginKind::Collider, colliders);
  read_plugin_list(root["constraints"], "constraints", PluginKind::Constraint, constraints);
  read_solver(root, solvers);
  read_output(root["output"], root["checkpoint"], scene);
  read_special_bonds(root["special_bonds"], scene);
  warn_unused_topology();
  if (!diags_.empty()) fail();

  // Assemble. Everything is valid as far as the descriptors can tell; the
  // factories may still refuse values (ParamError), reported the same way.
  assemble_system(scene);
  create_plugins(scene, forces, colliders, constraints, solvers);
  if (scene.solver && scene.solver->adaptive() && scene.neighbor_schedule != RebuildSchedule{}) {
    error(neighbor_node_, "simulation.neighbor",
          fmt::format("simulation.neighbor: a rebuild schedule counts fixed steps; {} chooses its "
                      "own step lengths (expected a fixed-step solver: verlet, rk4, euler, ...)",
                      scene.solver_label));
  }
  if (!diags_.empty()) fail();
  apply_special_bonds(scene);
  if (!diags_.empty()) fail();
  scene.warnings = std::move(warnings_);
  return scene;
}

// A constraint added to a running system (Python's sim.add_constraint); its
// pattern is checked against the system's particles.
void Loader::add_constraint_to(System& sys, PendingPlugin& p, const SceneContext& ctx,
                               const std::string& label) {
  auto c = create(p, [&] { return registry_.create_constraint(*p.record, p.params, ctx); });
  if (!c) fail();
  try {
    SystemAssembly(sys).add_constraint(std::move(c), label, p.compliance);
  } catch (const Error& e) {
    diags_.push_back({file_, fmt::format("{}: {}", p.path, e.what())});
    fail();
  }
}

// A solver replacing the scene's (Python's sim.set_solver), checked against
// the forces and constraints it will step.
void Loader::replace_solver(Scene& scene, PendingPlugin& p, const SceneContext& ctx,
                            const std::string& label) {
  System& sys = *scene.system;
  const std::string& name = p.record->descriptor->name;
  auto s = create(p, [&] { return registry_.create_solver(*p.record, p.params, ctx); });
  if (!s) fail();
  for (const auto& entry : sys.force_objects()) {
    const std::string why = fixed_step_conflict(*entry.force, entry.label, *s, name);
    if (!why.empty()) {
      diags_.push_back({file_, fmt::format("{}: {}", p.path, why)});
      fail();
    }
  }
  if (!honours_compliance(*s)) {
    const auto& rows = sys.evaluate_constraint_rows();
    if (rows.rows() > 0 && rows.compliance.maxCoeff() > 0.0) {
      diags_.push_back(
          {file_, fmt::format("{}: a constraint has a compliance, which '{}' cannot honour "
                              "(expected a solver that does, e.g. xpbd)",
                              p.path, name)});
      fail();
    }
  }
  SystemAssembly(sys).enable_constraint_force(!enforces_constraints(*s));
  scene.solver = std::move(s);
  scene.solver_name = name;
  scene.solver_label = label;
  scene.solver_params = p.params;
  scene.libraries[label] = p.record->library;
}

std::string Loader::add_to(Scene& scene, PluginKind kind, const std::string& text) {
  marks_ = false;
  System& sys = *scene.system;
  YAML::Node item;
  try {
    item = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    diags_.push_back(
        {file_, fmt::format("malformed parameters: {} (expected a YAML mapping)", e.msg)});
    fail();
  }
  const std::string path = kind_name(kind);
  if (!check_plugin_map(item, path, kind)) fail();
  const PluginRecord* rec = find_plugin(item, path, kind);
  if (!rec) fail();
  // Index parameters are checked against the system's particles now.
  x_.assign(static_cast<std::size_t>(sys.size()), Vec3::Zero());
  auto params = read_plugin_params(item, path, *rec, {});
  const auto compliance =
      kind == PluginKind::Constraint ? read_compliance(item, path) : std::optional<double>(0.0);
  if (!params || !compliance) fail();
  PendingPlugin p{rec, std::move(*params), item, path, *compliance};
  const SceneContext ctx{sys.view(), &scene.groups};
  const std::string name = rec->descriptor->name;
  std::string label = fmt::format("{} ({})", name, file_);
  switch (kind) {
    case PluginKind::Force: {
      auto f = create(p, [&] { return registry_.create_force(*rec, p.params, ctx); });
      if (!f) fail();
      if (const std::string why = special_bonds_refusal(*f, label, rec->library);
          scene.special_bonds && !why.empty()) {
        diags_.push_back({file_, fmt::format("{}: {} (the scene has special_bonds)", path, why)});
        fail();
      }
      if (scene.solver) {
        const std::string why = fixed_step_conflict(*f, name, *scene.solver, scene.solver_name);
        if (!why.empty()) {
          diags_.push_back({file_, fmt::format("{}: {}", path, why)});
          fail();
        }
      }
      SystemAssembly(sys).add_force(std::move(f), label);
      scene.force_traits[label] = rec->descriptor->force_traits;
      break;
    }
    case PluginKind::Collider: {
      auto c = create(p, [&] { return registry_.create_collider(*rec, p.params, ctx); });
      if (!c) fail();
      SystemAssembly(sys).add_collider(std::move(c), label);
      break;
    }
    case PluginKind::Constraint:
      if (p.compliance > 0.0 && scene.solver && !honours_compliance(*scene.solver)) {
        diags_.push_back({file_, fmt::format("{}.compliance: {} {}", path, p.compliance,
                                             compliance_conflict(scene.solver_name))});
        fail();
      }
      add_constraint_to(sys, p, ctx, label);
      break;
    case PluginKind::Solver:
      replace_solver(scene, p, ctx, label);
      return label;
    case PluginKind::Writer:  // writers belong to a scene's output list, not to its system
      diags_.push_back({file_, fmt::format("{}: '{}' is a writer (expected a force, collider, "
                                           "constraint or solver)",
                                           path, name)});
      fail();
  }
  scene.libraries[label] = rec->library;
  scene.uses.push_back({kind, name, label, std::move(p.params)});
  // A new pair force takes the scene's special bonds; new bonds (a force's
  // or a constraint's pairs) change them. A collider changes neither.
  if (kind == PluginKind::Force || kind == PluginKind::Constraint) apply_special_bonds(scene);
  return label;
}

}  // namespace loading

namespace {

// An object added after loading becomes part of what a checkpoint must
// match (resume.cpp compares the canonical texts): appended to the
// canonical text as an item of a last top-level key `added:`, its kind and
// its YAML, not its origin, which only names the caller. So a run resumed
// into a simulation without the object, with another, or with other
// parameters, is refused with the difference instead of going on silently.
// Appending keeps this linear in the number of additions; `added` is never
// a scene's own key (the schema refuses it), so it stays the last one.
void record_addition(Scene& scene, PluginKind kind, const std::string& text) {
  YAML::Node node = YAML::Load(text);
  node.SetStyle(YAML::EmitterStyle::Flow);  // one line, whatever style the caller wrote
  YAML::Emitter object;
  object << node;
  if (!scene.canonical_text.empty() && scene.canonical_text.back() != '\n') {
    scene.canonical_text += '\n';
  }
  // From the end: once there, `added:` is followed only by the additions.
  if (scene.canonical_text.rfind("\nadded:\n") == std::string::npos) {
    scene.canonical_text += "added:\n";
  }
  scene.canonical_text +=
      fmt::format("  - {{kind: {}, object: {}}}\n", kind_name(kind), object.c_str());
}

}  // namespace

std::string add_plugin(Scene& scene, const PluginRegistry& registry, PluginKind kind,
                       const std::string& text, const std::string& origin) {
  std::string label = loading::Loader(origin, registry, {}).add_to(scene, kind, text);
  record_addition(scene, kind, text);
  return label;
}

namespace {

// Hands the heap pages the load freed back to the system. A load builds the
// particles and the builders' pair lists in growing vectors, next to the
// YAML tree; glibc keeps what they freed resident (blocks below its dynamic
// mmap threshold, up to 32 MB, live in the heap), under the run's own
// buffers: 48 of the 503 bytes per particle at the peak of a 1000 x 1000
// cloth run (issue 32, item 4). A walk of the heap's free lists: far less
// than a millisecond after a small scene.
void return_freed_memory() {
#ifdef __GLIBC__
  malloc_trim(0);
#endif
}

}  // namespace

Scene load_scene_text(const std::string& text, const std::string& file,
                      const PluginRegistry& registry, const std::vector<Override>& overrides) {
  Scene scene = loading::Loader(file, registry, overrides).load(text);
  return_freed_memory();
  return scene;
}

Scene load_scene(const std::filesystem::path& file, const PluginRegistry& registry,
                 const std::vector<Override>& overrides) {
  std::ifstream in(file, std::ios::binary);
  if (!in) {
    throw SceneError({{file.string(),
                       "cannot read the scene file (expected a readable YAML "
                       "file)"}});
  }
  std::ostringstream ss;
  ss << in.rdbuf();
  return load_scene_text(ss.str(), file.string(), registry, overrides);
}

}  // namespace pdyn
