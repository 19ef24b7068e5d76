// Parameter resolution: defaults, required, types, bounds (see pdyn/host/resolve.hpp).
#include "pdyn/host/resolve.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "pdyn/text.hpp"

namespace pdyn {

namespace {

std::string num(double x) { return fmt::format("{}", x); }

// The spec of one number inside a vector or list: the same bounds and unit.
ParamSpec element_spec(const ParamSpec& spec) {
  ParamSpec e = spec;
  e.type = spec.type == ParamType::IntegerList ? ParamType::Integer : ParamType::Real;
  return e;
}

class Checker {
 public:
  Checker(const ParamSpec& spec, std::vector<ParamProblem>& out) : spec_(spec), out_(out) {}

  // One number; false (and a problem) if it is not finite or out of bounds.
  bool number(double x, std::vector<std::size_t> element, std::string key = {}) {
    const ParamSpec e = element_spec(spec_);
    if (!std::isfinite(x)) {
      add(ParamProblem::Kind::NotFinite, std::move(element), std::move(key), x,
          fmt::format("{} is not finite (expected {})", num(x), expectation(e)));
      return false;
    }
    const bool below = spec_.min && (spec_.min_exclusive ? x <= *spec_.min : x < *spec_.min);
    const bool above = spec_.max && x > *spec_.max;
    if (below || above) {
      add(ParamProblem::Kind::OutOfRange, std::move(element), std::move(key), x,
          fmt::format("{} is out of range (expected {})", num(x),
                      spec_.type == ParamType::Integer ? expectation(spec_) : expectation(e)));
      return false;
    }
    return true;
  }

  // A vector: the first bad component, then not_zero.
  void vector(const Vec3& v, std::vector<std::size_t> prefix) {
    for (std::size_t k = 0; k < 3; ++k) {
      auto at = prefix;
      at.push_back(k);
      if (!number(v[static_cast<Index>(k)], std::move(at))) return;
    }
    if (spec_.nonzero && v.norm() == 0.0) {
      add(ParamProblem::Kind::ZeroVector, std::move(prefix), {}, 0.0,
          fmt::format("is the zero vector (expected {})", expectation(spec_)));
    }
  }

  void add(ParamProblem::Kind kind, std::vector<std::size_t> element, std::string key, double value,
           std::string message) {
    out_.push_back({kind, spec_.name, std::move(element), std::move(key), value,
                    fmt::format("parameter '{}': {}", spec_.name, message)});
  }

 private:
  const ParamSpec& spec_;
  std::vector<ParamProblem>& out_;
};

// ParamType's enumerators are in the order of ParamValue's alternatives.
bool has_type(const ParamValue& v, ParamType t) { return v.index() == static_cast<std::size_t>(t); }

void check_value(const ParamSpec& spec, const ParamValue& value, std::vector<ParamProblem>& out) {
  Checker check(spec, out);
  switch (spec.type) {
    case ParamType::Real:
      check.number(std::get<double>(value), {});
      break;
    case ParamType::Integer:
      check.number(static_cast<double>(std::get<std::int64_t>(value)), {});
      break;
    case ParamType::Vector:
      check.vector(std::get<Vec3>(value), {});
      break;
    case ParamType::RealList: {
      const auto& xs = std::get<std::vector<double>>(value);
      for (std::size_t e = 0; e < xs.size(); ++e) check.number(xs[e], {e});
      break;
    }
    case ParamType::VectorList: {
      const auto& vs = std::get<std::vector<Vec3>>(value);
      for (std::size_t e = 0; e < vs.size(); ++e) check.vector(vs[e], {e});
      break;
    }
    case ParamType::NamedReals:
      for (const auto& [name, x] : std::get<NamedReals>(value)) check.number(x, {}, name);
      break;
    case ParamType::IntegerList: {
      const auto& is = std::get<IntegerValues>(value);
      for (std::size_t e = 0; e < is.size(); ++e) check.number(static_cast<double>(is[e]), {e});
      break;
    }
    default:  // strings, booleans and particle indices have no bounds here
      break;
  }
}

}  // namespace

Resolved resolve(const std::vector<ParamSpec>& specs, const Params& given) {
  Resolved r;
  for (const auto& spec : specs) {
    const auto it = given.values().find(spec.name);
    const ParamValue* value = nullptr;
    if (it != given.values().end()) {
      value = &it->second;
    } else if (spec.fallback) {
      value = &*spec.fallback;
    } else {
      if (spec.required) {
        r.problems.push_back(
            {ParamProblem::Kind::Missing,
             spec.name,
             {},
             {},
             0.0,
             fmt::format("missing required parameter '{}' (expected {}{})", spec.name,
                         expectation(spec), spec.doc.empty() ? "" : ": " + spec.doc)});
      }
      continue;
    }
    r.params.set(spec.name, *value);
    if (!has_type(*value, spec.type)) {
      r.problems.push_back({ParamProblem::Kind::WrongType,
                            spec.name,
                            {},
                            {},
                            0.0,
                            fmt::format("parameter '{}' is not {} (expected {})", spec.name,
                                        describe(spec.type), expectation(spec))});
      continue;
    }
    check_value(spec, *value, r.problems);
  }
  for (const auto& entry : given.values()) {
    // Named members, not a structured binding: clang 14 cannot capture a binding in a lambda.
    const std::string& name = entry.first;
    const ParamValue& value = entry.second;
    const bool declared =
        std::any_of(specs.begin(), specs.end(), [&](const ParamSpec& s) { return s.name == name; });
    if (!declared) {
      r.params.set(name, value);
      std::vector<std::string> names;
      names.reserve(specs.size());
      for (const auto& s : specs) names.push_back(s.name);
      r.problems.push_back(
          {ParamProblem::Kind::Unknown,
           name,
           {},
           {},
           0.0,
           fmt::format("unknown parameter '{}' (expected one of: {})", name, join(names))});
    }
  }
  return r;
}

std::string expectation(const ParamSpec& s) {
  std::string e = describe(s.type);
  if (s.min && s.max) {
    e += fmt::format(" in {}{}, {}]", s.min_exclusive ? "(" : "[", num(*s.min), num(*s.max));
  } else if (s.min) {
    e += fmt::format(" {} {}", s.min_exclusive ? ">" : ">=", num(*s.min));
  } else if (s.max) {
    e += fmt::format(" <= {}", num(*s.max));
  }
  if (s.nonzero) e += ", not zero";
  if (!s.unit.empty()) e += " in " + s.unit;
  return e;
}

}  // namespace pdyn
