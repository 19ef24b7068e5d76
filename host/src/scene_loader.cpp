// The scene loader: YAML text -> validated, assembled Scene.
//
// The whole file is checked before anything is simulated, and every problem
// found is reported, each as `FILE:LINE:COLUMN: what is wrong (what was
// expected)`. Built-in sections (simulation, particles, grid, output) are
// described by the same ParamSpec lists that plugins use for their
// parameters, so one reader checks types, ranges, required and unknown keys
// everywhere.
#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <set>
#include <sstream>

#include "pdyn/host/runner.hpp"
#include "pdyn/host/scene.hpp"
#include "pdyn/host/scene_specs.hpp"
#include "pdyn/host/side_files.hpp"
#include "pdyn/resolve.hpp"
#include "pdyn/text.hpp"
#include "scene_builders.hpp"
#include "written_paths.hpp"

namespace pdyn {

namespace fs = std::filesystem;

SceneError::SceneError(std::vector<Diagnostic> diagnostics)
    : Error([&] {
        std::string s;
        for (std::size_t i = 0; i < diagnostics.size(); ++i) {
          s += (i ? "\n" : "") + diagnostics[i].text();
        }
        return s;
      }()),
      diagnostics_(std::move(diagnostics)) {}

Override parse_override(const std::string& text) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0) {
    throw SceneError({{"--set " + text,
                       "an override needs a key path and a value "
                       "(expected KEY.PATH=VALUE, e.g. simulation.dt=0.001)"}});
  }
  return {text.substr(0, eq), text.substr(eq + 1)};
}

// ---------------------------------------------------------------------------
// Specifications of the built-in sections (scene_specs.hpp: `pdyn schema`
// reads them too).

std::vector<ParamSpec> simulation_specs() {
  return {
      param::required_real("dt", "s", "time step").greater_than(0),
      param::optional("steps", ParamType::Integer, "", "number of steps (or give duration)")
          .at_least(0),
      param::optional("duration", ParamType::Real, "s", "simulated time (or give steps)")
          .at_least(0),
      param::optional("threads", ParamType::Integer, "",
                      "threads for forces and solvers (default: all cores; pdyn run --threads "
                      "overrides it); results do not depend on it")
          .at_least(1)
          .at_most(1024),
  };
}

std::vector<ParamSpec> particle_specs() {
  return {
      param::required_vec3("position", "m", "initial position"),
      param::vec3("velocity", Vec3::Zero(), "m/s", "initial velocity"),
      param::required_real("mass", "kg", "mass").greater_than(0),
      param::boolean("fixed", false, "nailed in place"),
  };
}

std::vector<ParamSpec> grid_specs() {
  ParamSpec nx = param::required("nx", ParamType::Integer, "", "particles along u");
  ParamSpec ny = param::required("ny", ParamType::Integer, "", "particles along v");
  nx.at_least(1);
  ny.at_least(1);
  return {
      param::required_vec3("origin", "m", "position of particle (0, 0)"),
      param::required_vec3("u", "m", "spacing vector along the first grid direction").not_zero(),
      param::required_vec3("v", "m", "spacing vector along the second grid direction").not_zero(),
      nx,
      ny,
      param::required_real("mass", "kg", "mass of each particle").greater_than(0),
      param::vec3("velocity", Vec3::Zero(), "m/s", "initial velocity of every particle"),
      param::optional("name", ParamType::String, "", "group name"),
      param::optional("pin", ParamType::IndexPairs, "",
                      "grid coordinates [i, j] of nailed particles; negative counts from the end"),
  };
}

std::vector<ParamSpec> output_specs() {
  ParamSpec every = param::integer("every", 1, "a frame every N steps; 0: first and final only");
  every.at_least(0);
  return {
      param::optional("path", ParamType::String, "", "frames CSV: t,id,x,y,z,vx,vy,vz"),
      every,
      param::optional("energy", ParamType::String, "", "energy CSV: t,kinetic,potential,total"),
  };
}

std::vector<ParamSpec> checkpoint_specs() {
  ParamSpec every = param::integer("every", 0, "a checkpoint every N steps; 0: at the end only");
  every.at_least(0);
  return {param::required("path", ParamType::String, "", "checkpoint file"), every};
}

std::vector<BuilderSpec> builder_specs() {
  std::vector<BuilderSpec> all = {
      {"grid",
       "a rectangular sheet of nx x ny particles, optionally joined by springs",
       grid_specs(),
       {{"springs",
         "Provot's spring families of the `spring` plugin",
         "spring",
         "pairs",
         {"structural", "shear", "bend"},
         {}}}}};
  for (auto& b : more_builder_specs()) all.push_back(std::move(b));
  return all;
}

namespace {

// The most particles a scene may hold: about 3.5 GB of kernel state, far
// beyond any interactive scene, and a clear refusal instead of an
// out-of-memory failure for a mistyped grid size.
constexpr std::int64_t kMaxParticles = std::int64_t{1} << 24;

std::vector<std::string> spec_names(const std::vector<ParamSpec>& specs) {
  std::vector<std::string> names;
  for (const auto& s : specs) names.push_back(s.name);
  return names;
}

// A value as the user wrote it, for a message: the scalar itself, or a list
// or mapping in YAML's flow style ("[0, 0]"), shortened if long. Quoting a
// description ("'a list or mapping'") instead reads as if it were the value.
std::string shown(const YAML::Node& n) {
  if (n.IsScalar()) return n.Scalar();
  if (!n.IsDefined() || n.IsNull()) return "~";
  YAML::Emitter e;
  e.SetSeqFormat(YAML::Flow);
  e.SetMapFormat(YAML::Flow);
  e << n;
  std::string text = e.c_str();
  constexpr std::size_t kMax = 60;
  if (text.size() > kMax) text = text.substr(0, kMax - 3) + "...";
  return text;
}

// What yaml-cpp's terse parser messages usually mean, as the expectation.
std::string yaml_hint(const std::string& text, const YAML::ParserException& e) {
  std::istringstream lines(text);
  std::string line;
  for (int i = 0; i <= e.mark.line; ++i) {
    if (!std::getline(lines, line)) line.clear();
  }
  const auto indent = line.find_first_not_of(" \t");
  if (line.substr(0, indent).find('\t') != std::string::npos) {
    return "expected indentation with spaces: YAML does not allow tabs there";
  }
  const std::string& m = e.msg;
  if (m == "illegal map value") {
    return "expected 'key: value' lines of one mapping indented alike, with spaces";
  }
  if (m == "illegal flow end") {
    return "expected every '[' closed by ']' and every '{' by '}', innermost first";
  }
  if (m == "end of map flow not found") return "expected a '}' closing the '{'";
  if (m == "end of sequence flow not found") return "expected a ']' closing the '['";
  if (m == "end of map not found" || m == "end of sequence not found") {
    return "expected the entries of one mapping or list indented alike";
  }
  return "expected valid YAML";
}

// The innermost '{' or '[' still open where the parser stopped, if it was
// opened on an earlier line: a flow collection left unclosed is reported by
// yaml-cpp where it gave up (often the next list item, lines later), while
// the mistake is where the bracket was opened. Quoted scalars and comments
// are skipped; lines and columns are 0-based, like YAML::Mark.
struct OpenBracket {
  char bracket;
  int line, column;
};
std::optional<OpenBracket> unclosed_flow(const std::string& text, const YAML::Mark& stop) {
  std::vector<OpenBracket> open;
  int line = 0, column = 0;
  char quote = 0;
  bool comment = false;
  char previous = '\n';
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (line > stop.line || (line == stop.line && column >= stop.column)) break;
    const char c = text[i];
    if (c == '\n') {
      ++line;
      column = 0;
      comment = false;
      previous = c;
      continue;
    }
    if (comment) {
    } else if (quote) {
      if (quote == '"' && c == '\\') {
        ++i;
        ++column;
      } else if (c == quote) {
        quote = 0;
      }
    } else if (c == '#' && (previous == ' ' || previous == '\t' || previous == '\n')) {
      comment = true;
    } else if (c == '"' || c == '\'') {
      quote = c;
    } else if (c == '{' || c == '[') {
      open.push_back({c, line, column});
    } else if ((c == '}' || c == ']') && !open.empty()) {
      open.pop_back();
    }
    previous = c;
    ++column;
  }
  if (open.empty() || open.back().line >= stop.line) return std::nullopt;
  return open.back();
}

// A queued force or collider: created once all particles exist.
struct PendingPlugin {
  const PluginRecord* record;
  Params params;
  YAML::Node node;
  std::string path;
};

class Loader final : public BuilderHost {
 public:
  Loader(std::string file, const PluginRegistry& registry, std::vector<Override> overrides)
      : file_(std::move(file)), registry_(registry), overrides_(std::move(overrides)) {}

  Scene load(const std::string& text);

 private:
  // ---- diagnostics ----
  std::string where(const YAML::Node& at, const std::string& path) const;
  void error(const YAML::Node& at, const std::string& path, std::string message) override;
  [[noreturn]] void fail();

  // ---- generic readers ----
  bool check_map(const YAML::Node& n, const std::string& path, const char* what) override;
  bool check_plugin_map(const YAML::Node& n, const std::string& path, PluginKind kind);
  void check_keys(const YAML::Node& map, const std::string& path,
                  const std::vector<std::string>& allowed);
  std::optional<ParamValue> read_value(const YAML::Node& n, const std::string& path,
                                       const ParamSpec& spec, Index n_particles);
  std::optional<double> read_number(const YAML::Node& n, const std::string& path,
                                    const ParamSpec& spec);
  std::optional<ParamValue> read_named_reals(const YAML::Node& n, const std::string& path,
                                             const ParamSpec& spec);
  std::optional<std::int64_t> read_integer(const YAML::Node& n, const std::string& path,
                                           const ParamSpec& spec);
  std::optional<Index> read_index(const YAML::Node& n, const std::string& path, Index n_particles);
  std::optional<Vec3> read_vec3(const YAML::Node& n, const std::string& path,
                                const ParamSpec& spec);
  template <std::size_t K>
  std::optional<std::vector<std::array<Index, K>>> read_tuples(const YAML::Node& n,
                                                               const std::string& path,
                                                               Index n_particles);
  /// Reads the keys of `map` described by `specs`; `extra` keys are allowed
  /// and left to the caller. Index-typed values are checked against
  /// n_particles when it is >= 0.
  void locate(const YAML::Node& map, const std::string& path, const ParamSpec& spec,
              const ParamProblem& problem);
  std::optional<Params> read_params(const YAML::Node& map, const std::string& path,
                                    const std::vector<ParamSpec>& specs,
                                    const std::vector<std::string>& extra, Index n_particles);

  // ---- BuilderHost: what the builders of scene_builders.cpp may use ----
  std::optional<Params> read_params(const YAML::Node& map, const std::string& path,
                                    const std::vector<ParamSpec>& specs,
                                    const std::vector<std::string>& extra) override {
    return read_params(map, path, specs, extra, -1);
  }
  Index particle_count() const override { return static_cast<Index>(x_.size()); }
  bool can_add(std::int64_t count, const YAML::Node& at, const std::string& path) override;
  void add_particle(const Vec3& x, const Vec3& v, double mass, bool fixed) override {
    x_.push_back(x);
    v_.push_back(v);
    m_.push_back(mass);
    fixed_.push_back(fixed ? 1 : 0);
  }
  void set_fixed(Index id) override { fixed_[static_cast<std::size_t>(id)] = 1; }
  Vec3 position(Index id) const override { return x_[static_cast<std::size_t>(id)]; }
  void add_group(const std::string& name, std::vector<Index> members, const YAML::Node& at,
                 const std::string& path) override;
  void add_force(const std::string& plugin, const YAML::Node& node, const std::string& path,
                 const Params& generated, const Params& defaults, bool create) override;

  // ---- sections ----
  void apply_overrides(YAML::Node& root);
  void read_simulation(const YAML::Node& n, Scene& scene);
  void read_particles(const YAML::Node& n);
  void read_grid(const YAML::Node& n, const std::string& path);
  // ---- side files (side_files.hpp) ----
  std::optional<fs::path> side_file(const YAML::Node& map, const std::string& path,
                                    const char* expected);
  void read_particle_file(const YAML::Node& item, const std::string& path);
  const PluginRecord* find_plugin(const YAML::Node& item, const std::string& path, PluginKind kind);
  void read_plugin_list(const YAML::Node& n, const char* section, PluginKind kind,
                        std::vector<PendingPlugin>& out);
  std::optional<Params> read_plugin_params(const YAML::Node& item, const std::string& path,
                                           const PluginRecord& rec,
                                           const std::vector<std::string>& generated);
  void read_output(const YAML::Node& n, Scene& scene);
  void check_written_files(const YAML::Node& n, const Scene& scene);
  template <class Create>
  auto create(const PendingPlugin& p, Create&& create_fn) -> decltype(create_fn());

  std::string file_;
  const PluginRegistry& registry_;
  std::vector<Override> overrides_;
  std::vector<Diagnostic> diags_;
  YAML::Node root_;  // the whole scene: where a missing section is reported

  // particles as read
  std::vector<Vec3> x_, v_;
  std::vector<double> m_;
  std::vector<std::uint8_t> fixed_;
  std::map<std::string, std::vector<Index>> groups_;
  std::vector<PendingPlugin> builder_forces_;  // springs made by builders
  bool particles_ok_ = true;
  std::vector<NamedPath> read_files_;  // side files: no output may overwrite them
};

// ---------------------------------------------------------------------------
// Diagnostics

bool path_within(const std::string& path, const std::string& prefix) {
  if (path.rfind(prefix, 0) != 0) return false;
  return path.size() == prefix.size() || path[prefix.size()] == '.' || path[prefix.size()] == '[';
}

std::string Loader::where(const YAML::Node& at, const std::string& path) const {
  // A value that came from --set has no place in the file: name the override.
  for (auto it = overrides_.rbegin(); it != overrides_.rend(); ++it) {
    if (path_within(path, it->path)) return fmt::format("--set {}={}", it->path, it->value);
  }
  if (at.IsDefined()) {
    const YAML::Mark m = at.Mark();
    if (m.line >= 0) return fmt::format("{}:{}:{}", file_, m.line + 1, m.column + 1);
  }
  // Nor does a mapping that --set created on the way to its value.
  for (auto it = overrides_.rbegin(); it != overrides_.rend(); ++it) {
    if (path_within(it->path, path)) return fmt::format("--set {}={}", it->path, it->value);
  }
  return file_;
}

// bash expands an unquoted `~` after `=` in a word such as `output=~`, so
// `--set output=~` arrives as `output=/home/NAME`. A value that is the home
// folder, or a path inside it, refused by a key is most likely that.
bool looks_like_home(const std::string& value) {
  const char* env = std::getenv("HOME");
  const std::string home = env ? env : "";
  if (home.empty() || home == "/") return false;
  return value == home || value.rfind(home + "/", 0) == 0;
}

void Loader::error(const YAML::Node& at, const std::string& path, std::string message) {
  std::string loc = where(at, path);
  for (const auto& ov : overrides_) {
    if (loc != fmt::format("--set {}={}", ov.path, ov.value) || !looks_like_home(ov.value)) {
      continue;
    }
    constexpr const char* hint = "did you mean null? the shell expands ~ to your home folder";
    if (const auto open = message.rfind(" ("); open != std::string::npos && message.back() == ')') {
      message.insert(open + 2, std::string(hint) + "; ");
    } else {
      message += fmt::format(" ({})", hint);
    }
    break;
  }
  diags_.push_back({std::move(loc), std::move(message)});
}

void Loader::fail() { throw SceneError(diags_); }

// ---------------------------------------------------------------------------
// Generic readers

bool Loader::check_map(const YAML::Node& n, const std::string& path, const char* what) {
  if (n.IsMap()) return true;
  if (n.IsScalar() || n.IsSequence()) {
    error(n, path, fmt::format("{}: '{}' is not a mapping (expected {})", path, shown(n), what));
  } else {
    error(n, path, fmt::format("{}: is not a mapping (expected {})", path, what));
  }
  return false;
}

// A plugin entry, { type: NAME, ... }. `solver: verlet` or `- gravity` is
// the plugin's name alone: suggest the mapping it was meant to be.
bool Loader::check_plugin_map(const YAML::Node& n, const std::string& path, PluginKind kind) {
  if (n.IsMap()) return true;
  const char* what = "{ type: NAME, parameters... }";
  if (n.IsScalar() && registry_.find(kind, n.Scalar())) {
    error(n, path,
          fmt::format("{}: '{}' is not a mapping (did you mean {{ type: {} }}? expected {})", path,
                      n.Scalar(), n.Scalar(), what));
    return false;
  }
  return check_map(n, path, what);
}

void Loader::check_keys(const YAML::Node& map, const std::string& path,
                        const std::vector<std::string>& allowed) {
  std::map<std::string, YAML::Mark> seen;  // where each key was first given
  for (const auto& kv : map) {
    const std::string key = kv.first.Scalar();
    const std::string key_path = path.empty() ? key : path + "." + key;
    if (const auto [first, inserted] = seen.emplace(key, kv.first.Mark()); !inserted) {
      // A --set value has no mark (line -1): it replaced the key, never repeats one.
      const YAML::Mark m = first->second;
      error(kv.first, key_path,
            fmt::format("duplicate key '{}' in {} (expected each key once; the first is at "
                        "{}:{})",
                        key, path.empty() ? "the scene" : path, m.line + 1, m.column + 1));
      continue;
    }
    if (std::find(allowed.begin(), allowed.end(), key) != allowed.end()) continue;
    const std::string guess = closest_match(key, allowed);
    error(
        kv.first, key_path,
        fmt::format("unknown key '{}' in {} ({}expected one of: {})", key,
                    path.empty() ? "the scene" : path,
                    guess.empty() ? "" : fmt::format("did you mean '{}'? ", guess), join(allowed)));
  }
}

// Readers convert YAML to values of the spec's type and report what is not
// of it; finiteness, bounds and defaults are resolve()'s (pdyn/resolve.hpp),
// whose problems read_params() locates.
std::optional<double> Loader::read_number(const YAML::Node& n, const std::string& path,
                                          const ParamSpec& spec) {
  double x = 0;
  if (!n.IsScalar() || !YAML::convert<double>::decode(n, x)) {
    error(n, path,
          fmt::format("{}: '{}' is not a number (expected {})", path, shown(n), expectation(spec)));
    return std::nullopt;
  }
  return x;
}

std::optional<std::int64_t> Loader::read_integer(const YAML::Node& n, const std::string& path,
                                                 const ParamSpec& spec) {
  long long x = 0;
  if (!n.IsScalar() || !YAML::convert<long long>::decode(n, x)) {
    error(n, path,
          fmt::format("{}: '{}' is not a whole number (expected {})", path, shown(n),
                      expectation(spec)));
    return std::nullopt;
  }
  return static_cast<std::int64_t>(x);
}

std::optional<Index> Loader::read_index(const YAML::Node& n, const std::string& path,
                                        Index n_particles) {
  long long i = 0;
  if (!n.IsScalar() || !YAML::convert<long long>::decode(n, i)) {
    error(
        n, path,
        fmt::format("{}: '{}' is not a particle index (expected a whole number)", path, shown(n)));
    return std::nullopt;
  }
  if (n_particles >= 0 && (i < 0 || i >= n_particles)) {
    error(n, path,
          fmt::format("{}: particle index {} is out of range (expected 0..{}: the scene has {})",
                      path, i, n_particles - 1, count_of(n_particles, "particle")));
    return std::nullopt;
  }
  return static_cast<Index>(i);
}

std::optional<Vec3> Loader::read_vec3(const YAML::Node& n, const std::string& path,
                                      const ParamSpec& spec) {
  if (!n.IsSequence() || n.size() != 3) {
    // Say what was found: a list of the wrong length, or another kind of value.
    const std::string found = n.IsSequence()
                                  ? "it has " + count_of(static_cast<long long>(n.size()), "number")
                              : n.IsMap() ? fmt::format("it is the mapping {}", shown(n))
                                          : fmt::format("it is '{}'", shown(n));
    error(n, path,
          fmt::format("{}: is not a 3-vector: {} (expected {})", path, found, expectation(spec)));
    return std::nullopt;
  }
  ParamSpec element = spec;  // bounds apply to each component
  element.type = ParamType::Real;
  Vec3 v;
  for (int k = 0; k < 3; ++k) {
    auto c = read_number(n[k], fmt::format("{}[{}]", path, k), element);
    if (!c) return std::nullopt;
    v[k] = *c;
  }
  return v;
}

template <std::size_t K>
std::optional<std::vector<std::array<Index, K>>> Loader::read_tuples(const YAML::Node& n,
                                                                     const std::string& path,
                                                                     Index n_particles) {
  const char* expected = K == 2 ? "a list of particle index pairs [[i, j], ...]"
                                : "a list of particle index triples [[i, j, k], ...]";
  if (n.IsMap()) {  // { file: pairs.csv }, a CSV side file
    const auto file = side_file(
        n, path,
        K == 2 ? "{ file: pairs.csv } with header i,j" : "{ file: triples.csv } with header i,j,k");
    if (!file) return std::nullopt;
    return side_files::read_tuples<K>(*file, file->string(), n_particles, diags_);
  }
  if (!n.IsSequence()) {
    error(n, path,
          fmt::format("{}: is not a list (expected {} or {{ file: NAME.csv }})", path, expected));
    return std::nullopt;
  }
  std::vector<std::array<Index, K>> out;
  out.reserve(n.size());
  bool ok = true;
  for (std::size_t e = 0; e < n.size(); ++e) {
    const YAML::Node t = n[e];
    const std::string ep = fmt::format("{}[{}]", path, e);
    if (!t.IsSequence() || t.size() != K) {
      error(t, ep, fmt::format("{}: is not a list of {} indices (expected {})", ep, K, expected));
      ok = false;
      continue;
    }
    std::array<Index, K> a{};
    for (std::size_t k = 0; k < K; ++k) {
      auto i = read_index(t[k], fmt::format("{}[{}]", ep, k), n_particles);
      if (!i) {
        ok = false;
        break;
      }
      a[k] = *i;
    }
    out.push_back(a);
  }
  if (!ok) return std::nullopt;
  return out;
}

std::optional<ParamValue> Loader::read_value(const YAML::Node& n, const std::string& path,
                                             const ParamSpec& spec, Index n_particles) {
  auto list_of = [&](auto&& read_one) -> std::optional<ParamValue> {
    using T = typename std::decay_t<decltype(*read_one(n, path))>;
    if (!n.IsSequence()) {
      error(n, path, fmt::format("{}: is not a list (expected {})", path, expectation(spec)));
      return std::nullopt;
    }
    std::vector<T> out;
    out.reserve(n.size());
    bool ok = true;
    for (std::size_t e = 0; e < n.size(); ++e) {
      auto x = read_one(n[e], fmt::format("{}[{}]", path, e));
      if (x)
        out.push_back(*x);
      else
        ok = false;
    }
    if (!ok) return std::nullopt;
    return ParamValue(std::move(out));
  };
  ParamSpec element = spec;
  switch (spec.type) {
    case ParamType::Real:
      if (auto x = read_number(n, path, spec)) return ParamValue(*x);
      return std::nullopt;
    case ParamType::Integer:
      if (auto x = read_integer(n, path, spec)) return ParamValue(*x);
      return std::nullopt;
    case ParamType::Boolean: {
      bool b = false;
      if (n.IsScalar() && YAML::convert<bool>::decode(n, b)) return ParamValue(b);
      // 0 and 1 too, as a CSV side file's `fixed` column takes them.
      if (n.IsScalar() && (n.Scalar() == "0" || n.Scalar() == "1")) {
        return ParamValue(n.Scalar() == "1");
      }
      error(n, path,
            fmt::format("{}: '{}' is not true or false (expected {})", path, shown(n),
                        expectation(spec)));
      return std::nullopt;
    }
    case ParamType::String:
      if (n.IsScalar()) return ParamValue(n.Scalar());
      error(n, path, fmt::format("{}: is not a string (expected {})", path, expectation(spec)));
      return std::nullopt;
    case ParamType::Vector:
      if (auto v = read_vec3(n, path, spec)) return ParamValue(*v);
      return std::nullopt;
    case ParamType::RealList:
      element.type = ParamType::Real;
      // A single number is the one-element list: `rest: 0.1` is `rest: [0.1]`,
      // "one for all" as the plugins that take such lists describe it.
      if (n.IsScalar()) {
        if (auto x = read_number(n, path, element)) return ParamValue(std::vector<double>{*x});
        return std::nullopt;
      }
      return list_of(
          [&](const YAML::Node& e, const std::string& p) { return read_number(e, p, element); });
    case ParamType::VectorList:
      element.type = ParamType::Vector;
      return list_of(
          [&](const YAML::Node& e, const std::string& p) { return read_vec3(e, p, element); });
    case ParamType::IndexList:
      return list_of(
          [&](const YAML::Node& e, const std::string& p) { return read_index(e, p, n_particles); });
    case ParamType::IndexPairs:
      if (auto t = read_tuples<2>(n, path, n_particles)) return ParamValue(std::move(*t));
      return std::nullopt;
    case ParamType::IndexTriples:
      if (auto t = read_tuples<3>(n, path, n_particles)) return ParamValue(std::move(*t));
      return std::nullopt;
    case ParamType::StringList:
      return list_of([&](const YAML::Node& e, const std::string& p) -> std::optional<std::string> {
        if (e.IsScalar()) return e.Scalar();
        error(e, p, fmt::format("{}: is not a string (expected {})", p, expectation(spec)));
        return std::nullopt;
      });
    case ParamType::NamedReals:
      return read_named_reals(n, path, spec);
  }
  return std::nullopt;
}

// { name: number, ... }: names are identifiers, so that a plugin can use
// them as variables (an expression's constants, say).
std::optional<ParamValue> Loader::read_named_reals(const YAML::Node& n, const std::string& path,
                                                   const ParamSpec& spec) {
  if (!n.IsMap()) {
    error(n, path, fmt::format("{}: is not a mapping (expected {})", path, expectation(spec)));
    return std::nullopt;
  }
  ParamSpec element = spec;
  element.type = ParamType::Real;
  NamedReals out;
  bool ok = true;
  for (const auto& kv : n) {
    const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : "";
    const std::string kp = fmt::format("{}.{}", path, key);
    const bool identifier = !key.empty() && !std::isdigit(static_cast<unsigned char>(key[0])) &&
                            std::all_of(key.begin(), key.end(), [](char c) {
                              return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
                            });
    if (!identifier) {
      error(kv.first, kp,
            fmt::format("{}: '{}' is not a name (expected letters, digits and '_', not starting "
                        "with a digit)",
                        path, shown(kv.first)));
      ok = false;
      continue;
    }
    auto x = read_number(kv.second, kp, element);
    if (!x) {
      ok = false;
      continue;
    }
    if (!out.emplace(key, *x).second) {
      error(kv.first, kp,
            fmt::format("{}: duplicate name '{}' (expected each name once)", path, key));
      ok = false;
    }
  }
  if (!ok) return std::nullopt;
  return ParamValue(std::move(out));
}

std::optional<Params> Loader::read_params(const YAML::Node& map, const std::string& path,
                                          const std::vector<ParamSpec>& specs,
                                          const std::vector<std::string>& extra,
                                          Index n_particles) {
  std::vector<std::string> allowed = spec_names(specs);
  allowed.insert(allowed.end(), extra.begin(), extra.end());
  const std::size_t before = diags_.size();
  check_keys(map, path, allowed);
  Params given;  // a key set to null (`key:` or `key: ~`) is not given: its default applies
  std::set<std::string> unreadable;
  for (const auto& spec : specs) {
    const YAML::Node n = map[spec.name];
    if (!n.IsDefined() || n.IsNull()) continue;
    if (auto value = read_value(n, path + "." + spec.name, spec, n_particles)) {
      given.set(spec.name, std::move(*value));
    } else {
      unreadable.insert(spec.name);  // reported; not "missing" as well
    }
  }
  Resolved resolved = resolve(specs, given);
  for (const auto& problem : resolved.problems) {
    if (unreadable.count(problem.param)) continue;
    const auto spec = std::find_if(specs.begin(), specs.end(),
                                   [&](const ParamSpec& s) { return s.name == problem.param; });
    if (spec != specs.end()) locate(map, path, *spec, problem);
  }
  if (diags_.size() != before) return std::nullopt;
  return std::move(resolved.params);
}

// One problem resolve() found, reported where the value was written, with
// the value as the user spelled it.
void Loader::locate(const YAML::Node& map, const std::string& path, const ParamSpec& spec,
                    const ParamProblem& problem) {
  using Kind = ParamProblem::Kind;
  YAML::Node node = map[spec.name];
  std::string p = path + "." + spec.name;
  if (problem.kind == Kind::Missing) {
    error(node.IsDefined() ? node : map, p,
          fmt::format("{}: missing required key '{}' (expected {}{})", path, spec.name,
                      expectation(spec), spec.doc.empty() ? "" : ": " + spec.doc));
    return;
  }
  if (!problem.key.empty()) {
    node = node[problem.key];
    p += "." + problem.key;
  }
  for (const std::size_t e : problem.element) {
    if (!node.IsSequence()) break;  // `rest: 0.1`, the one-element list written as a number
    node = node[e];
    p += fmt::format("[{}]", e);
  }
  ParamSpec element = spec;  // bounds apply to each number of a vector or list
  if (spec.type != ParamType::Integer) element.type = ParamType::Real;
  switch (problem.kind) {
    case Kind::NotFinite:
      error(node, p,
            fmt::format("{}: {} is not finite (expected {})", p, node.Scalar(),
                        expectation(element)));
      return;
    case Kind::OutOfRange:
      error(node, p,
            fmt::format("{}: {} is out of range (expected {})", p,
                        spec.type == ParamType::Integer
                            ? fmt::format("{}", static_cast<long long>(problem.value))
                            : node.Scalar(),
                        expectation(element)));
      return;
    case Kind::ZeroVector:
      element.type = ParamType::Vector;
      error(node, p, fmt::format("{}: is the zero vector (expected {})", p, expectation(element)));
      return;
    default:  // Missing is above; types and names were checked while reading
      error(node, p, fmt::format("{}: {}", p, problem.message));
      return;
  }
}

// ---------------------------------------------------------------------------
// --set overrides

void Loader::apply_overrides(YAML::Node& root) {
  for (const auto& ov : overrides_) {
    const std::string loc = fmt::format("--set {}={}", ov.path, ov.value);
    auto bad = [&](const std::string& msg) { diags_.push_back({loc, msg}); };
    // Split "forces[0].g" into keys and indices.
    struct Step {
      std::string key;
      long index = -1;
    };
    std::vector<Step> steps;
    std::string s = ov.path;
    bool ok = true;
    std::size_t i = 0;
    while (i < s.size() && ok) {
      if (s[i] == '.') {
        ++i;
        continue;
      }
      if (s[i] == '[') {
        const auto close = s.find(']', i);
        long idx = -1;
        try {
          std::size_t used = 0;
          idx = std::stol(s.substr(i + 1, close - i - 1), &used);
          ok = close != std::string::npos && used == close - i - 1 && idx >= 0;
        } catch (const std::exception&) {
          ok = false;
        }
        steps.push_back({"", idx});
        i = close == std::string::npos ? s.size() : close + 1;
        continue;
      }
      const auto end = s.find_first_of(".[", i);
      steps.push_back({s.substr(i, end - i), -1});
      i = end == std::string::npos ? s.size() : end;
    }
    if (!ok || steps.empty()) {
      bad(fmt::format("malformed key path '{}' (expected keys and [index]es, e.g. forces[0].g)",
                      ov.path));
      continue;
    }
    YAML::Node value;
    try {
      value = YAML::Load(ov.value);
    } catch (const YAML::Exception& e) {
      bad(
          fmt::format("the value is not valid YAML: {} (expected a YAML value, e.g. 0.5 or "
                      "[0, 0, -9.81])",
                      e.msg));
      continue;
    }
    YAML::Node cur;
    cur.reset(root);
    std::string walked;
    for (std::size_t k = 0; k < steps.size() && ok; ++k) {
      const Step& st = steps[k];
      const bool last = k + 1 == steps.size();
      if (st.index >= 0) {
        const std::string here = walked.empty() ? "the scene" : walked;
        if (!cur.IsSequence()) {
          bad(fmt::format(
              "{} is {}, so it has no element [{}] (expected a key path into "
              "the scene's existing lists)",
              here, cur.IsDefined() && !cur.IsNull() ? "not a list" : "not in the scene",
              st.index));
          ok = false;
          break;
        }
        if (static_cast<std::size_t>(st.index) >= cur.size()) {
          bad(fmt::format("{} has no element [{}] (expected an index below {})", here, st.index,
                          cur.size()));
          ok = false;
          break;
        }
        walked += fmt::format("[{}]", st.index);
        if (last) {
          cur[st.index] = value;
        } else {
          YAML::Node next = cur[st.index];
          cur.reset(next);
        }
      } else {
        if (!(cur.IsMap() || cur.IsNull())) {
          bad(
              fmt::format("{} is not a mapping, so it has no key '{}' (expected a key path "
                          "that follows the scene's mappings)",
                          walked, st.key));
          ok = false;
          break;
        }
        walked += (walked.empty() ? "" : ".") + st.key;
        if (last) {
          cur[st.key] = value;
        } else {
          // A missing mapping on the way is created: --set output.path=... works
          // for a scene without an output section.
          YAML::Node next = cur[st.key];
          if (!next.IsDefined() && steps[k + 1].index < 0) {
            next = YAML::Node(YAML::NodeType::Map);
          }
          cur.reset(next);
        }
      }
    }
  }
}

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
  auto p = read_params(n, "simulation", simulation_specs(), {"solver"}, -1);
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
    if (item["file"].IsDefined()) {  // a CSV side file (side_files.hpp)
      read_particle_file(item, path);
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
      read_grid(item["grid"], path + ".grid");
      continue;
    }
    auto p = read_params(item, path, specs, {}, -1);
    if (!p) continue;
    x_.push_back(p->vec3("position"));
    v_.push_back(p->vec3("velocity"));
    m_.push_back(p->real("mass"));
    fixed_.push_back(p->boolean("fixed") ? 1 : 0);
  }
  if (diags_.size() != before) particles_ok_ = false;
  if (particles_ok_ && x_.empty()) {
    error(n, "particles",
          "particles: the scene has no particles (expected at least one "
          "particle or builder)");
    particles_ok_ = false;
  }
}

// The `file` of a side-file mapping, relative to the scene's folder.
std::optional<fs::path> Loader::side_file(const YAML::Node& map, const std::string& path,
                                          const char* expected) {
  check_keys(map, path, {"file"});
  const YAML::Node f = map["file"];
  if (!f.IsScalar() || f.Scalar().empty()) {
    error(f.IsDefined() ? f : map, path + ".file",
          fmt::format("{}.file: is not a file name (expected {})", path, expected));
    return std::nullopt;
  }
  const fs::path name(f.Scalar());
  fs::path file = name.is_absolute() ? name : fs::path(file_).parent_path() / name;
  read_files_.push_back({path + ".file", where(f, path + ".file"), file});
  return file;
}

void Loader::read_particle_file(const YAML::Node& item, const std::string& path) {
  const auto file = side_file(item, path, "{ file: particles.csv } with header x,y,z,mass");
  if (!file) return;
  auto rows = side_files::read_particles(*file, file->string(), diags_);
  if (!rows) return;
  if (static_cast<std::int64_t>(x_.size() + rows->x.size()) > kMaxParticles) {
    error(item, path,
          fmt::format("{}: {} particles is too many (expected at most {} particles "
                      "in a scene)",
                      path, x_.size() + rows->x.size(), kMaxParticles));
    return;
  }
  x_.insert(x_.end(), rows->x.begin(), rows->x.end());
  v_.insert(v_.end(), rows->v.begin(), rows->v.end());
  m_.insert(m_.end(), rows->mass.begin(), rows->mass.end());
  fixed_.insert(fixed_.end(), rows->fixed.begin(), rows->fixed.end());
}

// A rectangular sheet of nx x ny particles at origin + i u + j v; particle
// (i, j) gets index base + j nx + i. Springs per Provot's cloth model:
// structural (neighbours), shear (diagonals), bend (second neighbours).
void Loader::read_grid(const YAML::Node& g, const std::string& path) {
  if (!check_map(g, path, "grid: { origin, u, v, nx, ny, mass, ... }")) return;
  auto p = read_params(g, path, grid_specs(), {"springs"}, -1);
  if (!p) return;
  const std::int64_t nx = p->integer("nx"), ny = p->integer("ny");
  if (nx > kMaxParticles || ny > kMaxParticles ||
      static_cast<std::int64_t>(x_.size()) + nx * ny > kMaxParticles) {
    error(g, path,
          fmt::format("{}: {} x {} particles is too many (expected at most {} particles "
                      "in a scene)",
                      path, nx, ny, kMaxParticles));
    return;
  }
  const Index base = static_cast<Index>(x_.size());
  auto id = [&](std::int64_t i, std::int64_t j) { return base + j * nx + i; };
  const Vec3 origin = p->vec3("origin"), u = p->vec3("u"), v = p->vec3("v");
  const Vec3 vel = p->vec3("velocity");
  const double mass = p->real("mass");
  std::vector<Index> members;
  // Reserved up front: at a million particles, growing these vectors (and
  // the spring lists below) by doubling costs more than filling them.
  const std::size_t count = static_cast<std::size_t>(nx * ny);
  members.reserve(count);
  x_.reserve(x_.size() + count);
  v_.reserve(v_.size() + count);
  m_.reserve(m_.size() + count);
  fixed_.reserve(fixed_.size() + count);
  for (std::int64_t j = 0; j < ny; ++j) {
    for (std::int64_t i = 0; i < nx; ++i) {
      x_.push_back(origin + static_cast<double>(i) * u + static_cast<double>(j) * v);
      v_.push_back(vel);
      m_.push_back(mass);
      fixed_.push_back(0);
      members.push_back(id(i, j));
    }
  }
  if (p->has("pin")) {
    const auto& pins = p->pairs("pin");
    for (std::size_t k = 0; k < pins.size(); ++k) {
      std::int64_t i = pins[k][0], j = pins[k][1];
      if (i < 0) i += nx;
      if (j < 0) j += ny;
      if (i < 0 || i >= nx || j < 0 || j >= ny) {
        error(g["pin"][k], fmt::format("{}.pin[{}]", path, k),
              fmt::format("{}.pin[{}]: [{}, {}] is outside the {} x {} grid (expected i in "
                          "-{}..{}, j in -{}..{})",
                          path, k, pins[k][0], pins[k][1], nx, ny, nx, nx - 1, ny, ny - 1));
        continue;
      }
      fixed_[static_cast<std::size_t>(id(i, j))] = 1;
    }
  }
  if (p->has("name")) {
    const std::string& name = p->string("name");
    if (!groups_.emplace(name, std::move(members)).second) {
      error(g["name"], path + ".name",
            fmt::format("{}.name: group '{}' is already defined (expected a unique name)", path,
                        name));
    }
  }
  const YAML::Node springs = g["springs"];
  if (!springs.IsDefined() || springs.IsNull()) return;
  const std::string sp = path + ".springs";
  if (!check_map(springs, sp, "springs: { structural: { ks, kd }, shear: {...}, bend: {...} }")) {
    return;
  }
  check_keys(springs, sp, {"structural", "shear", "bend"});
  const PluginRecord* spring = nullptr;
  for (const char* family : {"structural", "shear", "bend"}) {
    const YAML::Node s = springs[family];
    if (!s.IsDefined() || s.IsNull()) continue;
    const std::string fp = sp + "." + family;
    if (!check_map(s, fp, "{ ks: N/m, kd: N s/m }")) continue;
    if (!spring) {
      registry_.require_healthy("spring");
      spring = registry_.find(PluginKind::Force, "spring");
      if (!spring) {
        error(s, fp,
              fmt::format("{}: grid springs need the 'spring' force plugin, which was "
                          "not found (expected it on the plugin path)",
                          fp));
        return;
      }
    }
    std::vector<IndexPair> pairs;
    const char kind = family[1];  // 't'ructural, 'h'ear, 'e'nd: no string compare per particle
    pairs.reserve(static_cast<std::size_t>(2 * nx * ny));
    for (std::int64_t j = 0; j < ny; ++j) {
      for (std::int64_t i = 0; i < nx; ++i) {
        if (kind == 't') {
          if (i + 1 < nx) pairs.push_back({id(i, j), id(i + 1, j)});
          if (j + 1 < ny) pairs.push_back({id(i, j), id(i, j + 1)});
        } else if (kind == 'h') {
          if (i + 1 < nx && j + 1 < ny) {
            pairs.push_back({id(i, j), id(i + 1, j + 1)});
            pairs.push_back({id(i + 1, j), id(i, j + 1)});
          }
        } else {
          if (i + 2 < nx) pairs.push_back({id(i, j), id(i + 2, j)});
          if (j + 2 < ny) pairs.push_back({id(i, j), id(i, j + 2)});
        }
      }
    }
    // Checked even when the grid is too small for this family, so that a
    // typo is reported whatever the grid's size.
    auto params = read_plugin_params(s, fp, *spring, {"pairs"});
    if (!params || pairs.empty()) continue;
    params->set("pairs", std::move(pairs));
    builder_forces_.push_back({spring, std::move(*params), s, fp});
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

void Loader::add_force(const std::string& plugin, const YAML::Node& node, const std::string& path,
                       const Params& generated, const Params& defaults, bool create) {
  registry_.require_healthy(plugin);
  const PluginRecord* rec = registry_.find(PluginKind::Force, plugin);
  if (!rec) {
    error(node, path,
          fmt::format("{}: needs the '{}' force plugin, which was not found (expected it on the "
                      "plugin path)",
                      path, plugin));
    return;
  }
  std::vector<std::string> names;
  for (const auto& kv : generated.values()) names.push_back(kv.first);
  // A family left out entirely has no keys to check.
  const YAML::Node keys = node.IsDefined() && node.IsMap() ? node : YAML::Node(YAML::NodeType::Map);
  auto params = read_plugin_params(keys, path, *rec, names);
  if (!params || !create) return;
  for (const auto& [key, value] : defaults.values()) {
    if (!keys[key].IsDefined() || keys[key].IsNull()) params->set(key, value);
  }
  for (const auto& [key, value] : generated.values()) params->set(key, value);
  builder_forces_.push_back({rec, std::move(*params), keys, path});
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
  const std::string name = t.Scalar();
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
  return read_params(item, path, specs,
                     is_builder ? std::vector<std::string>{} : std::vector<std::string>{"type"}, n);
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
    if (params) out.push_back({rec, std::move(*params), item, path});
  }
}

void Loader::read_output(const YAML::Node& n, Scene& scene) {
  if (!n.IsDefined() || n.IsNull()) return;
  if (!check_map(n, "output", "output: { path: FILE.csv, every: N, energy: FILE.csv }")) return;
  auto p = read_params(n, "output", output_specs(), {"checkpoint"}, -1);
  if (!p) return;
  // A file name, not a folder: found now rather than after the whole run.
  auto file_name = [&](const YAML::Node& at, const std::string& key_path, const std::string& v) {
    std::error_code ec;
    if (v.empty() || v.back() == '/' || fs::is_directory(v, ec)) {
      error(at, key_path,
            fmt::format("{}: '{}' is a folder, not a file (expected a file name, "
                        "e.g. out/run.csv)",
                        key_path, v));
      return false;
    }
    return true;
  };
  const YAML::Node c = n["checkpoint"];
  if (c.IsDefined() && !c.IsNull() &&
      check_map(c, "output.checkpoint", "checkpoint: { path: FILE.ckpt, every: N }")) {
    if (auto cp = read_params(c, "output.checkpoint", checkpoint_specs(), {}, -1)) {
      if (file_name(c["path"], "output.checkpoint.path", cp->string("path"))) {
        scene.output.checkpoint = cp->string("path");
      }
      scene.output.checkpoint_every = cp->integer("every");
    }
  }
  if (p->has("path") && file_name(n["path"], "output.path", p->string("path"))) {
    scene.output.path = p->string("path");
  }
  if (p->has("energy") && file_name(n["energy"], "output.energy", p->string("energy"))) {
    scene.output.energy = p->string("energy");
  }
  scene.output.every = p->integer("every");
  check_written_files(n, scene);
}

// Every file the run may write (written_paths.hpp), including the checkpoint
// an interrupted run writes when the scene names none, against each other,
// the scene file and the side files read so far.
void Loader::check_written_files(const YAML::Node& n, const Scene& scene) {
  std::vector<NamedPath> written;
  auto add = [&](const YAML::Node& at, const std::string& key, const fs::path& file,
                 bool beside_output = false) {
    if (!file.empty()) written.push_back({key, where(at, key), file, beside_output});
  };
  add(n["path"], "output.path", scene.output.path);
  add(n["energy"], "output.energy", scene.output.energy);
  if (!scene.output.checkpoint.empty()) {
    add(n["checkpoint"]["path"], "output.checkpoint.path", scene.output.checkpoint);
  } else if (!scene.output.path.empty()) {
    // Written only on an interrupt or a plugin fault: named so that the
    // user sees why, and how to choose another.
    add(n["path"],
        "the checkpoint of an interrupted run (output.path with .ckpt; set "
        "output.checkpoint.path to choose)",
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

Scene Loader::load(const std::string& text) {
  Scene scene;
  scene.file = file_;
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
                      "particles, and optionally output, forces, colliders)"});
    fail();
  }
  if (!root.IsMap()) {
    error(root, "",
          "the scene is not a mapping (expected the sections simulation, particles, "
          "and optionally output, forces, colliders)");
    fail();
  }
  apply_overrides(root);
  if (!diags_.empty()) fail();
  root_.reset(root);
  {
    // What a checkpoint must match: the scene after overrides, less the run
    // length, which a resumed run may extend, and the thread count.
    YAML::Node canonical = YAML::Clone(root);
    if (canonical["simulation"].IsMap()) {
      canonical["simulation"].remove("steps");
      canonical["simulation"].remove("duration");
      canonical["simulation"].remove("threads");  // bit-identical results for any count
    }
    YAML::Emitter emitter;
    emitter << canonical;
    scene.canonical_text = emitter.c_str();
  }

  check_keys(root, "", {"simulation", "output", "particles", "forces", "colliders"});
  read_simulation(root["simulation"], scene);
  read_particles(root["particles"]);
  std::vector<PendingPlugin> forces, colliders, solvers;
  read_plugin_list(root["forces"], "forces", PluginKind::Force, forces);
  read_plugin_list(root["colliders"], "colliders", PluginKind::Collider, colliders);
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
  read_output(root["output"], scene);
  if (!diags_.empty()) fail();

  // Assemble. Everything is valid as far as the descriptors can tell; the
  // factories may still refuse values (ParamError), reported the same way.
  const Index n = static_cast<Index>(x_.size());
  Matrix3X x(3, n), v(3, n);
  Eigen::VectorXd m(n);
  for (Index i = 0; i < n; ++i) {
    x.col(i) = x_[i];
    v.col(i) = v_[i];
    m(i) = m_[i];
  }
  scene.system = std::make_unique<System>();
  scene.system->set_particles(x, v, m, fixed_);
  scene.groups = groups_;
  const SceneContext ctx{scene.system->view(), &scene.groups};
  auto label = [&](const PendingPlugin& p) {
    return fmt::format("{} ({})", p.record->descriptor->name, where(p.node, p.path));
  };
  // Each object's parameters move into scene.uses once it exists: no copy
  // of a large spring list.
  auto keep = [&](PendingPlugin& p, PluginKind kind) {
    scene.uses.push_back({kind, p.record->descriptor->name, label(p), std::move(p.params)});
  };
  for (auto* list : {&builder_forces_, &forces}) {
    for (auto& p : *list) {
      auto f = create(p, [&] { return registry_.create_force(*p.record, p.params, ctx); });
      if (!f) continue;
      scene.system->add_force(std::move(f), label(p));
      scene.libraries[label(p)] = p.record->library;
      scene.force_traits[label(p)] = p.record->descriptor->force_traits;
      keep(p, PluginKind::Force);
    }
  }
  for (auto& p : colliders) {
    auto c = create(p, [&] { return registry_.create_collider(*p.record, p.params, ctx); });
    if (!c) continue;
    scene.system->add_collider(std::move(c), label(p));
    scene.libraries[label(p)] = p.record->library;
    keep(p, PluginKind::Collider);
  }
  for (const auto& p : solvers) {
    scene.solver = create(p, [&] { return registry_.create_solver(*p.record, p.params, ctx); });
    scene.solver_name = p.record->descriptor->name;
    scene.solver_label = label(p);
    scene.solver_params = p.params;
    scene.libraries[label(p)] = p.record->library;
  }
  if (!diags_.empty()) fail();
  return scene;
}

}  // namespace

Scene load_scene_text(const std::string& text, const std::string& file,
                      const PluginRegistry& registry, const std::vector<Override>& overrides) {
  return Loader(file, registry, overrides).load(text);
}

Scene load_scene(const fs::path& file, const PluginRegistry& registry,
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
