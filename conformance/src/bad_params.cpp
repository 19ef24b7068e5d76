// The check "bad parameters are rejected with a clear message".
//
// Bad values are generated from the descriptor alone (a wrong type for every
// parameter, a value just outside each declared bound, the zero vector where
// it is refused, a particle index past the end, each required key left out,
// and one unknown key) and fed to the real scene loader in a small scene
// text, through the same entry point `pdyn run` uses. So what is checked is
// exactly what a user of the plugin will see: a SceneError whose message names
// the offending key. The plugin sits where a scene holds its kind (`forces:`,
// `colliders:`, `output:`, the top-level `constraints:` list, or the
// simulation's solver). A baseline scene holding only the sample values must
// load, which also catches a descriptor whose own defaults break its own
// bounds.
#include <fmt/format.h>

#include <cmath>
#include <optional>

#include "checks.hpp"
#include "pdyn/host/registry.hpp"
#include "pdyn/host/scene.hpp"
#include "pdyn/system.hpp"
#include "sample.hpp"

namespace pdyn::conformance::detail {

namespace {

// A solver for the scenes of force, collider, writer and constraint plugins,
// which need one; the loader's default (rk4) is not in the kit's registry.
// Never stepped.
class NoStep final : public Solver {
 public:
  void step(System& sys, double h) override { sys.set_time(sys.time() + h); }
};

const PluginDescriptor& helper_solver() {
  static const PluginDescriptor d = [] {
    PluginDescriptor s;
    s.kind = PluginKind::Solver;
    s.name = "conformance_no_step";
    s.version = "1";
    s.description = "the conformance kit's placeholder solver";
    s.create_solver = [](const Params&, const SceneContext&) { return std::make_unique<NoStep>(); };
    return s;
  }();
  return d;
}

std::string quoted(const std::string& s) {
  std::string q = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') q += '\\';
    q += c;
  }
  return q + "\"";
}

std::string yaml_of(const ParamValue& v) {
  if (const auto* s = std::get_if<std::string>(&v)) return quoted(*s);
  return format_value(v);
}

struct BadCase {
  std::string key;
  std::string what;                  // "wrong type", "below the minimum", ...
  std::optional<std::string> value;  // YAML text; none: the key is left out
};

std::string num(double x) { return fmt::format("{}", x); }

// A number that breaks the spec's lower or upper bound, as YAML text.
std::optional<std::string> outside(const ParamSpec& s, bool below, bool integer) {
  if (below && s.min) {
    const double m = *s.min;
    if (!integer) return num(s.min_exclusive ? m : m - std::max(1.0, std::abs(m)));
    const double v = s.min_exclusive ? std::floor(m) : std::ceil(m) - 1;
    if (std::abs(v) < 9e18) return fmt::format("{}", static_cast<long long>(v));
  }
  if (!below && s.max) {
    const double m = *s.max;
    if (!integer) return num(m + std::max(1.0, std::abs(m)));
    const double v = std::floor(m) + 1;
    if (std::abs(v) < 9e18) return fmt::format("{}", static_cast<long long>(v));
  }
  return std::nullopt;
}

// (what is wrong, YAML value) pairs for one parameter.
using Values = std::vector<std::pair<std::string, std::string>>;

// A value of another type than the spec's (and, for named reals, a name
// that is no identifier).
Values wrong_types(const ParamSpec& s) {
  Values v;
  auto add = [&](std::string what, std::string value) {
    v.emplace_back(std::move(what), std::move(value));
  };
  switch (s.type) {
    case ParamType::Real:
      add("wrong type", "'abc'");
      break;
    case ParamType::Integer:
      add("wrong type", "0.5");
      break;
    case ParamType::Boolean:
      add("wrong type", "'maybe'");
      break;
    case ParamType::String:
    case ParamType::Vector:
      add("wrong type", "[1, 2]");
      break;
    case ParamType::RealList:
      add("wrong type", "'abc'");
      break;
    case ParamType::VectorList:
      add("wrong type", "[1, 2, 3]");
      break;
    case ParamType::IndexList:
      add("wrong type", "[0.5]");
      break;
    case ParamType::IndexPairs:
      add("wrong type", "[[0, 1, 2]]");
      break;
    case ParamType::IndexTriples:
      add("wrong type", "[[0, 1]]");
      break;
    case ParamType::IndexQuads:
      add("wrong type", "[[0, 1, 2]]");
      break;
    case ParamType::IntegerList:
      add("wrong type", "[0.5]");
      break;
    case ParamType::StringList:
      add("wrong type", "{ a: 1 }");
      break;
    case ParamType::NamedReals:
      add("wrong type", "[1, 2]");
      add("not an identifier", "{ 2x: 1 }");
      break;
  }
  return v;
}

// Numbers outside the spec's bounds, and the zero vector where it is refused.
Values out_of_bounds(const ParamSpec& s) {
  Values v;
  auto add = [&](std::string what, std::string value) {
    v.emplace_back(std::move(what), std::move(value));
  };
  const bool integer = s.type == ParamType::Integer || s.type == ParamType::IntegerList;
  for (bool below : {true, false}) {
    const auto x = outside(s, below, integer);
    if (!x) continue;
    const std::string what = below ? "below the minimum" : "above the maximum";
    switch (s.type) {
      case ParamType::Real:
      case ParamType::Integer:
        add(what, *x);
        break;
      case ParamType::Vector:
        add(what, fmt::format("[{0}, {0}, {0}]", *x));
        break;
      case ParamType::RealList:
      case ParamType::IntegerList:
        add(what, fmt::format("[{}]", *x));
        break;
      case ParamType::VectorList:
        add(what, fmt::format("[[{0}, {0}, {0}]]", *x));
        break;
      case ParamType::NamedReals:
        add(what, fmt::format("{{ a: {} }}", *x));
        break;
      default:
        break;
    }
  }
  const bool zero_in_range =
      (!s.min || (s.min_exclusive ? 0.0 > *s.min : 0.0 >= *s.min)) && (!s.max || 0.0 <= *s.max);
  if (s.nonzero && zero_in_range) {
    if (s.type == ParamType::Vector) add("the zero vector", "[0, 0, 0]");
    if (s.type == ParamType::VectorList) add("the zero vector", "[[0, 0, 0]]");
  }
  return v;
}

// Particle indices that are out of range or negative, for `n` particles.
Values bad_indices(const ParamSpec& s, Index n) {
  Values v;
  auto add = [&](std::string what, std::string value) {
    v.emplace_back(std::move(what), std::move(value));
  };
  switch (s.type) {
    case ParamType::IndexList:
      add("particle index out of range", fmt::format("[{}]", n));
      break;
    case ParamType::IndexPairs:
      add("particle index out of range", fmt::format("[[0, {}]]", n));
      add("negative particle index", "[[-1, 0]]");
      break;
    case ParamType::IndexTriples:
      add("particle index out of range", fmt::format("[[0, 1, {}]]", n));
      break;
    case ParamType::IndexQuads:
      add("particle index out of range", fmt::format("[[0, 1, 2, {}]]", n));
      break;
    default:
      break;
  }
  return v;
}

std::vector<BadCase> bad_cases(const PluginDescriptor& d, Index n) {
  std::vector<BadCase> cases;
  for (const auto& s : d.params) {
    for (const Values& values : {wrong_types(s), out_of_bounds(s), bad_indices(s, n)}) {
      for (const auto& [what, value] : values) cases.push_back({s.name, what, value});
    }
    if (s.required) cases.push_back({s.name, "required key left out", std::nullopt});
  }
  cases.push_back({"not_a_parameter", "unknown key", "1"});
  return cases;
}

// The scene: N particles at `x`, the plugin under test with `sample`, with
// `bad` applied (a key replaced, left out or added).
std::string scene_text(const PluginDescriptor& d, const Params& sample, const Matrix3X& x,
                       const BadCase* bad, std::string& item_path) {
  std::string item = fmt::format("type: {}\n", d.name);
  // A writer's own keys beside the host's: its file (never created, the
  // scene is only loaded) and its schedule.
  if (d.kind == PluginKind::Writer) item += "path: conformance-output.out\nevery: 1\n";
  bool placed = false;
  for (const auto& [key, value] : sample.values()) {
    if (bad && bad->key == key) {
      placed = true;
      if (bad->value) item += fmt::format("{}: {}\n", key, *bad->value);
      continue;
    }
    item += fmt::format("{}: {}\n", key, yaml_of(value));
  }
  if (bad && !placed && bad->value) item += fmt::format("{}: {}\n", bad->key, *bad->value);

  auto indent = [](const std::string& block, const std::string& first, const std::string& rest) {
    std::string out;
    std::size_t start = 0;
    for (bool head = true; start < block.size(); head = false) {
      const auto end = block.find('\n', start);
      out += (head ? first : rest) + block.substr(start, end - start) + "\n";
      start = end + 1;
    }
    return out;
  };
  std::string s = "simulation:\n  dt: 0.01\n  steps: 1\n  solver:\n";
  if (d.kind == PluginKind::Solver) {
    s += indent(item, "    ", "    ");
    item_path = "simulation.solver";
  } else {
    s += fmt::format("    type: {}\n", helper_solver().name);
  }
  s += "particles:\n";
  for (Index i = 0; i < x.cols(); ++i) {
    // Radii as in the kit's states, for contact laws (soft_contact).
    s += fmt::format("  - {{ position: [{}, {}, {}], mass: 1, radius: {} }}\n", x(0, i), x(1, i),
                     x(2, i), kRadius);
  }
  if (d.kind == PluginKind::Force) {
    s += "forces:\n" + indent(item, "  - ", "    ");
    item_path = "forces[0]";
  } else if (d.kind == PluginKind::Collider) {
    s += "colliders:\n" + indent(item, "  - ", "    ");
    item_path = "colliders[0]";
  } else if (d.kind == PluginKind::Writer) {
    s += "output:\n" + indent(item, "  - ", "    ");
    item_path = "output[0]";
  } else if (d.kind == PluginKind::Constraint) {
    s += "constraints:\n" + indent(item, "  - ", "    ");
    item_path = "constraints[0]";
  }
  return s;
}

}  // namespace

CheckResult check_bad_params(const PluginDescriptor& d, const Params& sample, const Matrix3X& x) {
  const std::string name = "params.bad_rejected";
  PluginRegistry registry;
  if (!registry.add(d, "(plugin under test)")) {
    return {
        name, Verdict::Fail, 1, 0,
        fmt::format("the registry refuses the descriptor: {}", registry.faults().back().message)};
  }
  if (d.kind != PluginKind::Solver && !registry.add(helper_solver(), "(conformance kit)")) {
    return {name, Verdict::Fail, 1, 0,
            fmt::format("cannot set up the scene: {}", registry.faults().back().message)};
  }
  std::string path;
  const std::string file = "conformance.yaml";
  try {
    (void)load_scene_text(scene_text(d, sample, x, nullptr, path), file, registry);
  } catch (const std::exception& e) {
    std::string first = e.what();
    first = first.substr(0, first.find('\n'));
    return {name, Verdict::Fail, 1, 0,
            fmt::format("a scene with the defaults and sample values is refused: {}", first)};
  }

  const auto cases = bad_cases(d, x.cols());
  std::size_t failed = 0;
  std::string first_problem;
  for (const auto& c : cases) {
    const std::string text = scene_text(d, sample, x, &c, path);
    const std::string shown =
        fmt::format("{}.{} {}{}", path, c.key, c.what, c.value ? " (" + *c.value + ")" : "");
    std::string problem;
    try {
      (void)load_scene_text(text, file, registry);
      problem = fmt::format("{} was accepted", shown);
    } catch (const SceneError& e) {
      bool named = false;
      for (const auto& diag : e.diagnostics()) {
        const std::string& m = diag.message;
        named = named || m.find(fmt::format("'{}'", c.key)) != std::string::npos ||
                m.find(fmt::format("{}.{}", path, c.key)) != std::string::npos;
      }
      if (!named) {
        problem = fmt::format("{} was refused without naming '{}': {}", shown, c.key,
                              e.diagnostics().empty() ? "" : e.diagnostics().front().message);
      }
    } catch (const std::exception& e) {
      problem = fmt::format("{} was refused with a non-scene error: {}", shown, e.what());
    }
    if (problem.empty()) continue;
    ++failed;
    if (first_problem.empty()) first_problem = problem;
  }
  if (failed == 0) {
    return {name, Verdict::Pass, 0, 0,
            fmt::format("{} bad values from the descriptor (wrong types, out of range, missing, "
                        "unknown key): each refused by the scene loader, naming its key",
                        cases.size())};
  }
  return {name, Verdict::Fail, static_cast<double>(failed), 0,
          fmt::format("{} of {} bad values: first: {}", failed, cases.size(), first_problem)};
}

}  // namespace pdyn::conformance::detail
