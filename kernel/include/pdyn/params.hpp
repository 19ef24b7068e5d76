// pdyn/params.hpp — typed plugin parameters and their specifications.
//
// A plugin declares its parameters once, in its descriptor; the scene loader
// checks a scene's values against that declaration (type, range, required,
// unknown keys, particle indices in range) and hands the factory a Params of
// already-checked values. Plugin code never parses YAML.
#pragma once

#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "pdyn/export.hpp"
#include "pdyn/types.hpp"

namespace pdyn {

enum class ParamType {
  Real,          ///< a number
  Integer,       ///< a whole number
  Boolean,       ///< true or false
  String,        ///< a string
  Vector,        ///< [x, y, z]
  RealList,      ///< [a, b, ...]
  VectorList,    ///< [[x, y, z], ...]
  IndexList,     ///< [i, j, ...] particle indices, checked against N
  IndexPairs,    ///< [[i, j], ...] particle indices, checked against N
  IndexTriples,  ///< [[i, j, k], ...] particle indices, checked against N
  StringList,    ///< ["a", "b", ...] strings (e.g. expressions)
  NamedReals,    ///< { name: number, ... } names [A-Za-z_][A-Za-z0-9_]*, each once
  // Added in 0.7.0 (ABI 6): at the end, so that the values above keep their
  // numbers and ParamValue's alternatives above keep their indices.
  IndexQuads,   ///< [[i, j, k, l], ...] particle indices, checked against N
  IntegerList,  ///< [a, b, ...] whole numbers (e.g. a type per bonded term)
};

/// The value of a NamedReals parameter: name -> number, in name order.
using NamedReals = std::map<std::string, double, std::less<>>;

/// The value of an IntegerList parameter. A type of its own, not
/// std::vector<std::int64_t>: that is IndexList's std::vector<Index>, and
/// ParamValue's alternatives must differ.
struct PDYN_API IntegerValues : std::vector<std::int64_t> {
  using std::vector<std::int64_t>::vector;
};

using ParamValue = std::variant<double, std::int64_t, bool, std::string, Vec3, std::vector<double>,
                                std::vector<Vec3>, std::vector<Index>, std::vector<IndexPair>,
                                std::vector<IndexTriple>, std::vector<std::string>, NamedReals,
                                std::vector<IndexQuad>, IntegerValues>;

/// How one parameter is spelled, typed, bounded and documented.
struct PDYN_API ParamSpec {
  /// YAML key: a letter or '_', then letters, digits or '_' ([A-Za-z_][A-Za-z0-9_]*,
  /// e.g. `G`, `k_spring`), never `type`, which names the plugin. The registry
  /// refuses a library that declares another name, and says why.
  std::string name;
  ParamType type = ParamType::Real;
  std::optional<ParamValue> fallback;  ///< default value; none: required or optional
  bool required = false;               ///< must appear in the scene
  std::string unit;                    ///< SI unit ("N/m"), empty if dimensionless
  std::string doc;                     ///< one line for `pdyn plugins describe`
  std::optional<double> min, max;      ///< bounds on a number or on each element
  bool min_exclusive = false;          ///< min is a strict bound (> instead of >=)
  bool nonzero = false;                ///< for Vec3: the zero vector is refused
  /// A typical value, used instead of the default by the conformance kit
  /// (`pdyn check`) to build the plugin, e.g. for a required expression
  /// that has no sensible default. Bounds are not checked against it.
  std::optional<ParamValue> sample;

  /// Fluent bounds: `param::real("ks", 1.0, "N/m", "...").at_least(0)`.
  ParamSpec& at_least(double lo) {
    min = lo;
    min_exclusive = false;
    return *this;
  }
  ParamSpec& greater_than(double lo) {
    min = lo;
    min_exclusive = true;
    return *this;
  }
  ParamSpec& at_most(double hi) {
    max = hi;
    return *this;
  }
  ParamSpec& not_zero() {
    nonzero = true;
    return *this;
  }
  ParamSpec& with_sample(ParamValue v) {
    sample = std::move(v);
    return *this;
  }
};

/// Short constructors for ParamSpec. A spec with a default is optional; one
/// made with `required_*` must be given; `optional_*` has no default and the
/// plugin asks Params::has().
namespace param {
PDYN_API ParamSpec real(std::string name, double fallback, std::string unit, std::string doc);
PDYN_API ParamSpec required_real(std::string name, std::string unit, std::string doc);
PDYN_API ParamSpec integer(std::string name, std::int64_t fallback, std::string doc);
/// A RealList whose default is the one-element list [fallback] (since 0.7.0).
PDYN_API ParamSpec real_list(std::string name, double fallback, std::string unit, std::string doc);
PDYN_API ParamSpec boolean(std::string name, bool fallback, std::string doc);
PDYN_API ParamSpec string(std::string name, std::string fallback, std::string doc);
PDYN_API ParamSpec vec3(std::string name, Vec3 fallback, std::string unit, std::string doc);
PDYN_API ParamSpec required_vec3(std::string name, std::string unit, std::string doc);
PDYN_API ParamSpec optional(std::string name, ParamType type, std::string unit, std::string doc);
PDYN_API ParamSpec required(std::string name, ParamType type, std::string unit, std::string doc);
}  // namespace param

/// The checked values of one plugin instance's parameters.
class PDYN_API Params {
 public:
  bool has(std::string_view name) const;
  double real(std::string_view name) const;
  std::int64_t integer(std::string_view name) const;
  bool boolean(std::string_view name) const;
  const std::string& string(std::string_view name) const;
  Vec3 vec3(std::string_view name) const;
  const std::vector<double>& reals(std::string_view name) const;
  const std::vector<Vec3>& vec3s(std::string_view name) const;
  const std::vector<Index>& indices(std::string_view name) const;
  const std::vector<IndexPair>& pairs(std::string_view name) const;
  const std::vector<IndexTriple>& triples(std::string_view name) const;
  const std::vector<std::string>& strings(std::string_view name) const;
  const NamedReals& named_reals(std::string_view name) const;
  const std::vector<IndexQuad>& quads(std::string_view name) const;
  const std::vector<std::int64_t>& integers(std::string_view name) const;

  /// Host side: stores a checked value.
  void set(std::string name, ParamValue value);
  const std::map<std::string, ParamValue, std::less<>>& values() const noexcept { return values_; }

 private:
  const ParamValue& get(std::string_view name) const;
  template <class T>
  const T& as(std::string_view name) const;
  std::map<std::string, ParamValue, std::less<>> values_;
};

// ---- checks and defaults that factories of multi-particle forces share ----

/// Throws ParamError at the first element of the pair, triple or quad list `key`
/// that names one particle twice (a spring from a particle to itself, a
/// triangle with a repeated corner): no geometry to act along.
PDYN_API void require_distinct_particles(const Params& params, std::string_view key);

/// Throws ParamError at the first element of the IndexList `key` that names
/// a particle already listed: "particle 3 is listed twice (expected each id
/// once)", `twice` saying how ("is pinned twice"). A per-particle constraint
/// listing a particle twice has equal rows, and J W J^T is then singular; a
/// selection that lists it twice would act on it twice.
PDYN_API void require_distinct_ids(const Params& params, std::string_view key,
                                   std::string_view twice = "is listed twice");

/// Rest values (lengths in m, angles in rad, areas in m^2) of `n` elements
/// of a force: the RealList `key` with one value for all or one per element,
/// or, when the scene leaves it out, initial(s) for each element s (the
/// configuration the scene starts in is at rest). `elements` names them in
/// the message ("pairs", "triples") when the count fits neither.
PDYN_API std::vector<double> rest_values(const Params& params, std::string_view key, std::size_t n,
                                         std::string_view elements,
                                         const std::function<double(std::size_t)>& initial);

/// "a number", "[x, y, z]", ... — how a scene spells a value of this type.
PDYN_API const char* describe(ParamType type);
/// "real", "vec3", ... — the type's short name in listings and schemas.
PDYN_API const char* type_name(ParamType type);
/// A value as YAML flow text ("[0, 0, -9.81]"), for listings and docs.
PDYN_API std::string format_value(const ParamValue& value);

}  // namespace pdyn
