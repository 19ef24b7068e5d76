// The generic YAML reader of scenes: diagnostics located at FILE:LINE:COLUMN,
// key checks, and the conversion of YAML values to the types of ParamSpecs.
// Defaults, bounds and required keys are resolve()'s (pdyn/host/resolve.hpp):
// read_params() converts, resolves, and reports each problem where the value
// was written, as the user spelled it.
#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <set>

#include "loader.hpp"
#include "pdyn/host/side_files.hpp"
#include "pdyn/text.hpp"

namespace pdyn::loading {

std::vector<std::string> spec_names(const std::vector<ParamSpec>& specs) {
  std::vector<std::string> names;
  names.reserve(specs.size());
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
    if (m.line >= 0 && marks_) return fmt::format("{}:{}:{}", file_, m.line + 1, m.column + 1);
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
    std::string guess = closest_match(key, allowed);
    // A builder's `radius`, `type` are `particle_radius`, `particle_type`.
    if (guess.empty() &&
        std::find(allowed.begin(), allowed.end(), "particle_" + key) != allowed.end()) {
      guess = "particle_" + key;
    }
    error(
        kv.first, key_path,
        fmt::format("unknown key '{}' in {} ({}expected one of: {})", key,
                    path.empty() ? "the scene" : path,
                    guess.empty() ? "" : fmt::format("did you mean '{}'? ", guess), join(allowed)));
  }
}

// Readers convert YAML to values of the spec's type and report what is not
// of it; finiteness, bounds and defaults are resolve()'s (pdyn/host/resolve.hpp),
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
  static_assert(K >= 2 && K <= 4);
  const char* expected = K == 2   ? "a list of particle index pairs [[i, j], ...]"
                         : K == 3 ? "a list of particle index triples [[i, j, k], ...]"
                                  : "a list of particle index quadruples [[i, j, k, l], ...]";
  if (n.IsMap()) {  // { file: pairs.csv }, a CSV side file, or a data file's section
    // Without format:, a data file is one its extension names, or the file of
    // a `particles: - file:` entry read as a data file (LAMMPS's data.NAME).
    const YAML::Node format = n["format"], name = n["file"];
    const bool named = name.IsDefined() && name.IsScalar() && !name.Scalar().empty();
    const bool data =
        format.IsDefined()
            ? format.IsScalar() && format.Scalar() == "lammps_data"
            : named && (import_files::format_of_extension(name.Scalar()) ==
                            import_files::Format::LammpsData ||
                        topology_.count(scene_relative(name.Scalar()).lexically_normal().string()));
    if (data) return read_data_terms<K>(n, path);
    const auto file = side_file(n, path,
                                K == 2   ? "{ file: pairs.csv } with header i,j"
                                : K == 3 ? "{ file: triples.csv } with header i,j,k"
                                         : "{ file: quads.csv } with header i,j,k,l");
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

// true or false; 0 and 1 too, as a CSV side file's `fixed` column takes them.
std::optional<ParamValue> Loader::read_boolean(const YAML::Node& n, const std::string& path,
                                               const ParamSpec& spec) {
  bool b = false;
  if (n.IsScalar() && YAML::convert<bool>::decode(n, b)) return ParamValue(b);
  if (n.IsScalar() && (n.Scalar() == "0" || n.Scalar() == "1")) {
    return ParamValue(n.Scalar() == "1");
  }
  error(n, path,
        fmt::format("{}: '{}' is not true or false (expected {})", path, shown(n),
                    expectation(spec)));
  return std::nullopt;
}

// [x, ...] read element by element with read_one(node, path), which returns
// an optional element and reports a bad one; every bad element is reported.
template <class List, class ReadOne>
std::optional<List> Loader::read_list(const YAML::Node& n, const std::string& path,
                                      const ParamSpec& spec, ReadOne&& read_one) {
  if (!n.IsSequence()) {
    error(n, path, fmt::format("{}: is not a list (expected {})", path, expectation(spec)));
    return std::nullopt;
  }
  List out;
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
  return out;
}

std::optional<ParamValue> Loader::read_value(const YAML::Node& n, const std::string& path,
                                             const ParamSpec& spec, Index n_particles) {
  auto list_of = [&](auto&& read_one) -> std::optional<ParamValue> {
    using T = typename std::decay_t<decltype(*read_one(n, path))>;
    if (auto xs = read_list<std::vector<T>>(n, path, spec, read_one))
      return ParamValue(std::move(*xs));
    return std::nullopt;
  };
  ParamSpec element = spec;
  switch (spec.type) {
    case ParamType::Real:
      if (auto x = read_number(n, path, spec)) return ParamValue(*x);
      return std::nullopt;
    case ParamType::Integer:
      if (auto x = read_integer(n, path, spec)) return ParamValue(*x);
      return std::nullopt;
    case ParamType::Boolean:
      return read_boolean(n, path, spec);
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
    case ParamType::IndexQuads:
      if (auto t = read_tuples<4>(n, path, n_particles)) return ParamValue(std::move(*t));
      return std::nullopt;
    case ParamType::IntegerList:
      return read_integer_list(n, path, spec);
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

// [a, b, ...] of whole numbers; as for RealList, a single whole number is the
// one-element list.
std::optional<ParamValue> Loader::read_integer_list(const YAML::Node& n, const std::string& path,
                                                    const ParamSpec& spec) {
  ParamSpec element = spec;
  element.type = ParamType::Integer;
  if (n.IsScalar()) {
    if (auto x = read_integer(n, path, element)) return ParamValue(IntegerValues{*x});
    return std::nullopt;
  }
  auto xs = read_list<IntegerValues>(n, path, spec, [&](const YAML::Node& e, const std::string& p) {
    return read_integer(e, p, element);
  });
  if (xs) return ParamValue(std::move(*xs));
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
  data_types_.reset();
  for (const auto& spec : specs) {
    const YAML::Node n = map[spec.name];
    if (!n.IsDefined() || n.IsNull()) continue;
    if (auto value = read_value(n, path + "." + spec.name, spec, n_particles)) {
      given.set(spec.name, std::move(*value));
    } else {
      unreadable.insert(spec.name);  // reported; not "missing" as well
    }
  }
  if (data_types_) apply_data_types(map, path, specs, given);
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

}  // namespace pdyn::loading
