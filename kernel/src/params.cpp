// Typed plugin parameters: constructors for specs and checked accessors.
#include "pdyn/params.hpp"

#include <fmt/format.h>

#include <unordered_set>

#include "pdyn/error.hpp"

namespace pdyn {

namespace param {
namespace {
ParamSpec make(std::string name, ParamType type, std::string unit, std::string doc) {
  ParamSpec s;
  s.name = std::move(name);
  s.type = type;
  s.unit = std::move(unit);
  s.doc = std::move(doc);
  return s;
}
}  // namespace

ParamSpec real(std::string name, double fallback, std::string unit, std::string doc) {
  ParamSpec s = make(std::move(name), ParamType::Real, std::move(unit), std::move(doc));
  s.fallback = fallback;
  return s;
}
ParamSpec required_real(std::string name, std::string unit, std::string doc) {
  return required(std::move(name), ParamType::Real, std::move(unit), std::move(doc));
}
ParamSpec real_list(std::string name, double fallback, std::string unit, std::string doc) {
  ParamSpec s = make(std::move(name), ParamType::RealList, std::move(unit), std::move(doc));
  s.fallback = std::vector<double>{fallback};
  return s;
}
ParamSpec integer(std::string name, std::int64_t fallback, std::string doc) {
  ParamSpec s = make(std::move(name), ParamType::Integer, "", std::move(doc));
  s.fallback = fallback;
  return s;
}
ParamSpec boolean(std::string name, bool fallback, std::string doc) {
  ParamSpec s = make(std::move(name), ParamType::Boolean, "", std::move(doc));
  s.fallback = fallback;
  return s;
}
ParamSpec string(std::string name, std::string fallback, std::string doc) {
  ParamSpec s = make(std::move(name), ParamType::String, "", std::move(doc));
  s.fallback = std::move(fallback);
  return s;
}
ParamSpec vec3(std::string name, Vec3 fallback, std::string unit, std::string doc) {
  ParamSpec s = make(std::move(name), ParamType::Vector, std::move(unit), std::move(doc));
  s.fallback = fallback;
  return s;
}
ParamSpec required_vec3(std::string name, std::string unit, std::string doc) {
  return required(std::move(name), ParamType::Vector, std::move(unit), std::move(doc));
}
ParamSpec optional(std::string name, ParamType type, std::string unit, std::string doc) {
  return make(std::move(name), type, std::move(unit), std::move(doc));
}
ParamSpec required(std::string name, ParamType type, std::string unit, std::string doc) {
  ParamSpec s = make(std::move(name), type, std::move(unit), std::move(doc));
  s.required = true;
  return s;
}
}  // namespace param

bool Params::has(std::string_view name) const { return values_.find(name) != values_.end(); }

void Params::set(std::string name, ParamValue value) {
  values_.insert_or_assign(std::move(name), std::move(value));
}

const ParamValue& Params::get(std::string_view name) const {
  auto it = values_.find(name);
  if (it == values_.end()) {
    throw Error(
        fmt::format("parameter '{}' has no value (declare a default or check has())", name));
  }
  return it->second;
}

template <class T>
const T& Params::as(std::string_view name) const {
  const ParamValue& v = get(name);
  if (const T* p = std::get_if<T>(&v)) return *p;
  throw Error(fmt::format("parameter '{}' is read with the wrong type", name));
}

double Params::real(std::string_view name) const { return as<double>(name); }
std::int64_t Params::integer(std::string_view name) const { return as<std::int64_t>(name); }
bool Params::boolean(std::string_view name) const { return as<bool>(name); }
const std::string& Params::string(std::string_view name) const { return as<std::string>(name); }
Vec3 Params::vec3(std::string_view name) const { return as<Vec3>(name); }
const std::vector<double>& Params::reals(std::string_view name) const {
  return as<std::vector<double>>(name);
}
const std::vector<Vec3>& Params::vec3s(std::string_view name) const {
  return as<std::vector<Vec3>>(name);
}
const std::vector<Index>& Params::indices(std::string_view name) const {
  return as<std::vector<Index>>(name);
}
const std::vector<IndexPair>& Params::pairs(std::string_view name) const {
  return as<std::vector<IndexPair>>(name);
}
const std::vector<IndexTriple>& Params::triples(std::string_view name) const {
  return as<std::vector<IndexTriple>>(name);
}

const std::vector<std::string>& Params::strings(std::string_view name) const {
  return as<std::vector<std::string>>(name);
}
const NamedReals& Params::named_reals(std::string_view name) const { return as<NamedReals>(name); }
const std::vector<IndexQuad>& Params::quads(std::string_view name) const {
  return as<std::vector<IndexQuad>>(name);
}
const std::vector<std::int64_t>& Params::integers(std::string_view name) const {
  return as<IntegerValues>(name);
}

const char* describe(ParamType type) {
  switch (type) {
    case ParamType::Real:
      return "a number";
    case ParamType::Integer:
      return "a whole number";
    case ParamType::Boolean:
      return "true, false, 1 or 0";
    case ParamType::String:
      return "a string";
    case ParamType::Vector:
      return "a vector [x, y, z]";
    case ParamType::RealList:
      return "a number or a list of numbers [a, b, ...]";
    case ParamType::VectorList:
      return "a list of vectors [[x, y, z], ...]";
    case ParamType::IndexList:
      return "a list of particle indices [i, j, ...]";
    case ParamType::IndexPairs:
      return "a list of particle index pairs [[i, j], ...]";
    case ParamType::IndexTriples:
      return "a list of particle index triples [[i, j, k], ...]";
    case ParamType::StringList:
      return "a list of strings [\"a\", \"b\", ...]";
    case ParamType::NamedReals:
      return "a mapping of names to numbers { name: value, ... }";
    case ParamType::IndexQuads:
      return "a list of particle index quadruples [[i, j, k, l], ...]";
    case ParamType::IntegerList:
      return "a whole number or a list of whole numbers [a, b, ...]";
  }
  return "?";
}

const char* type_name(ParamType type) {
  switch (type) {
    case ParamType::Real:
      return "real";
    case ParamType::Integer:
      return "integer";
    case ParamType::Boolean:
      return "bool";
    case ParamType::String:
      return "string";
    case ParamType::Vector:
      return "vec3";
    case ParamType::RealList:
      return "real list";
    case ParamType::VectorList:
      return "vec3 list";
    case ParamType::IndexList:
      return "index list";
    case ParamType::IndexPairs:
      return "index pairs";
    case ParamType::IndexTriples:
      return "index triples";
    case ParamType::StringList:
      return "string list";
    case ParamType::NamedReals:
      return "named reals";
    case ParamType::IndexQuads:
      return "index quads";
    case ParamType::IntegerList:
      return "integer list";
  }
  return "?";
}

namespace {
std::string num(double x) { return fmt::format("{}", x); }
std::string vec(const Vec3& v) { return fmt::format("[{}, {}, {}]", v.x(), v.y(), v.z()); }
template <class T, class F>
std::string list(const std::vector<T>& xs, F f) {
  std::string s = "[";
  for (std::size_t i = 0; i < xs.size(); ++i) s += (i ? ", " : "") + f(xs[i]);
  return s + "]";
}
template <std::size_t K>
std::string tuple(const std::array<Index, K>& a) {
  std::string s = "[";
  for (std::size_t i = 0; i < K; ++i) s += (i ? ", " : "") + std::to_string(a[i]);
  return s + "]";
}
}  // namespace

std::string format_value(const ParamValue& value) {
  struct Visitor {
    std::string operator()(double x) const { return num(x); }
    std::string operator()(std::int64_t x) const { return std::to_string(x); }
    std::string operator()(bool x) const { return x ? "true" : "false"; }
    std::string operator()(const std::string& x) const { return x; }
    std::string operator()(const Vec3& x) const { return vec(x); }
    std::string operator()(const std::vector<double>& x) const { return list(x, num); }
    std::string operator()(const std::vector<Vec3>& x) const { return list(x, vec); }
    std::string operator()(const std::vector<Index>& x) const {
      return list(x, [](Index i) { return std::to_string(i); });
    }
    std::string operator()(const std::vector<IndexPair>& x) const { return list(x, tuple<2>); }
    std::string operator()(const std::vector<IndexTriple>& x) const { return list(x, tuple<3>); }
    std::string operator()(const std::vector<IndexQuad>& x) const { return list(x, tuple<4>); }
    std::string operator()(const IntegerValues& x) const {
      return list(x, [](std::int64_t i) { return std::to_string(i); });
    }
    std::string operator()(const std::vector<std::string>& x) const {
      return list(x, [](const std::string& e) { return "\"" + e + "\""; });
    }
    std::string operator()(const NamedReals& x) const {
      std::string s = "{";
      for (const auto& [key, real] : x) s += (s.size() > 1 ? ", " : " ") + key + ": " + num(real);
      return s + (x.empty() ? "}" : " }");
    }
  };
  return std::visit(Visitor{}, value);
}

void require_distinct_ids(const Params& params, std::string_view key, std::string_view twice) {
  const auto& ids = params.indices(key);
  std::unordered_set<Index> seen;
  for (std::size_t e = 0; e < ids.size(); ++e) {
    if (!seen.insert(ids[e]).second) {
      throw ParamError(std::string(key),
                       fmt::format("particle {} {} (expected each id once)", ids[e], twice),
                       static_cast<long>(e));
    }
  }
}

void require_distinct_particles(const Params& params, std::string_view key) {
  auto refuse = [&](std::size_t s, const std::string& message) {
    throw ParamError(std::string(key), message, static_cast<long>(s));
  };
  const auto it = params.values().find(key);
  const auto* pairs =
      it == params.values().end() ? nullptr : std::get_if<std::vector<IndexPair>>(&it->second);
  if (pairs) {
    for (std::size_t s = 0; s < pairs->size(); ++s) {
      if ((*pairs)[s][0] == (*pairs)[s][1]) {
        refuse(s, fmt::format("joins particle {} to itself (expected two different particles)",
                              (*pairs)[s][0]));
      }
    }
    return;
  }
  const auto* quads =
      it == params.values().end() ? nullptr : std::get_if<std::vector<IndexQuad>>(&it->second);
  if (quads) {
    for (std::size_t s = 0; s < quads->size(); ++s) {
      const auto [i, j, k, l] = (*quads)[s];
      if (i == j || i == k || i == l || j == k || j == l || k == l) {
        refuse(s, fmt::format("[{}, {}, {}, {}] repeats a particle (expected four different "
                              "particles)",
                              i, j, k, l));
      }
    }
    return;
  }
  const auto& triples = params.triples(key);  // throws for a missing or mistyped key
  for (std::size_t s = 0; s < triples.size(); ++s) {
    const auto [i, j, k] = triples[s];
    if (i == j || j == k || i == k) {
      refuse(s, fmt::format("[{}, {}, {}] repeats a particle (expected three different "
                            "particles)",
                            i, j, k));
    }
  }
}

std::vector<double> rest_values(const Params& params, std::string_view key, std::size_t n,
                                std::string_view elements,
                                const std::function<double(std::size_t)>& initial) {
  std::vector<double> rest(n);
  if (!params.has(key)) {
    for (std::size_t s = 0; s < n; ++s) rest[s] = initial(s);
    return rest;
  }
  const auto& given = params.reals(key);
  if (given.size() != 1 && given.size() != n) {
    throw ParamError(std::string(key),
                     fmt::format("has {} values for {} {} (expected 1 value for all, or {})",
                                 given.size(), n, elements, n));
  }
  for (std::size_t s = 0; s < n; ++s) rest[s] = given.size() == 1 ? given[0] : given[s];
  return rest;
}

}  // namespace pdyn
