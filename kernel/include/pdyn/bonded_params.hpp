// pdyn/bonded_params.hpp — the parameters every bonded plugin shares, read
// in one place (since 0.10.0): the term list, `types`, per-type
// coefficients and `rest`.
//
// A bonded plugin's factory calls read_bonded() for its terms (particle
// indices, each term's type, each term's rest value in the unit of the
// law's coordinate: m, rad, m^2) and bonded_coefficient() for each
// coefficient of each type, and declares bonded_types_param() among its
// parameters; BondedForce<Law> (pdyn/bonded_force.hpp) takes the result.
// Types are as LAMMPS's bond types: `types` gives each term a type
// 0..T-1, and every coefficient list is one value for all types or one per
// type. Errors name the key and the element (ParamError).
#pragma once

#include <array>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "pdyn/domain.hpp"
#include "pdyn/error.hpp"
#include "pdyn/export.hpp"
#include "pdyn/params.hpp"
#include "pdyn/plugin.hpp"
#include "pdyn/types.hpp"

namespace pdyn {

/// What a bonded plugin's factory reads from its parameters (read_bonded()).
template <int N>
struct BondedInput {
  std::vector<std::array<Index, N>> terms;  ///< each term's particles
  std::vector<double> rest;                 ///< each term's rest value
  std::vector<std::int32_t> types;          ///< each term's type, or empty: all type 0
  std::int32_t n_types = 1;                 ///< types given coefficients: 0..n_types-1
};

/// The number of term types the coefficient lists `keys` (RealList
/// parameters, each one value for all types or one per type) give: the
/// longest list's length. Throws ParamError on a list whose length is
/// neither 1 nor that.
PDYN_API std::int32_t bonded_type_count(const Params& params,
                                        std::initializer_list<std::string_view> keys);

/// Type t's value of the coefficient list `key` (its only value if it has
/// one).
PDYN_API double bonded_coefficient(const Params& params, std::string_view key, std::int32_t t);

/// Reads the parameters every bonded plugin shares, in one place: the term
/// list `terms_key` (IndexPairs, IndexTriples or IndexQuads for N = 2, 3,
/// 4; no particle twice in one term), `types` (IntegerList, optional: one
/// type per term, each with coefficients in `coefficient_keys`) and `rest`
/// (RealList, optional: one for all terms or one per term; default: each
/// term's `measure` at the scene's initial positions, each particle at its
/// image nearest the term's first in a periodic box). Throws ParamError
/// naming the key and element.
template <int N, class Measure>
BondedInput<N> read_bonded(const Params& params, const SceneContext& ctx,
                           std::string_view terms_key,
                           std::initializer_list<std::string_view> coefficient_keys,
                           Measure&& measure) {
  BondedInput<N> in;
  require_distinct_particles(params, terms_key);
  if (ctx.particles.size() > std::numeric_limits<std::int32_t>::max()) {
    throw ParamError(std::string(terms_key),
                     "a scene of " + std::to_string(ctx.particles.size()) +
                         " particles (expected at most 2147483647: bonded terms store 32-bit "
                         "particle ids)");
  }
  if constexpr (N == 2) {
    in.terms = params.pairs(terms_key);
  } else if constexpr (N == 3) {
    in.terms = params.triples(terms_key);
  } else {
    in.terms = params.quads(terms_key);
  }
  in.n_types = bonded_type_count(params, coefficient_keys);
  if (params.has("types")) {
    const auto& given = params.integers("types");
    if (given.size() != 1 && given.size() != in.terms.size()) {
      throw ParamError("types", std::string("has ") + std::to_string(given.size()) +
                                    " values for " + std::to_string(in.terms.size()) + " " +
                                    std::string(terms_key) + " (expected 1 value for all, or " +
                                    std::to_string(in.terms.size()) + ")");
    }
    for (std::size_t s = 0; s < given.size(); ++s) {
      if (given[s] < 0 || given[s] >= in.n_types) {
        std::string keys;
        for (const auto k : coefficient_keys) keys += (keys.empty() ? "" : ", ") + std::string(k);
        throw ParamError("types",
                         std::to_string(given[s]) + " is not a term type (expected 0.." +
                             std::to_string(in.n_types - 1) + ": " + keys + " give " +
                             std::to_string(in.n_types) + " type" + (in.n_types > 1 ? "s" : "") +
                             ")",
                         static_cast<long>(s));
      }
    }
    in.types.resize(in.terms.size());
    for (std::size_t s = 0; s < in.types.size(); ++s) {
      in.types[s] = static_cast<std::int32_t>(given.size() == 1 ? given[0] : given[s]);
    }
  }
  const auto& x = ctx.particles.x;
  const Domain& box = ctx.particles.domain;
  in.rest = rest_values(params, "rest", in.terms.size(), terms_key, [&](std::size_t s) {
    // As BondedForce measures a term: in a periodic box, each particle at
    // its image nearest the first.
    std::array<Vec3, N> at;
    at[0] = x.col(in.terms[s][0]);
    for (int a = 1; a < N; ++a) at[a] = box.nearest_image(x.col(in.terms[s][a]), at[0]);
    return measure(at);
  });
  return in;
}

/// The `types` parameter every bonded plugin declares (see read_bonded).
PDYN_API ParamSpec bonded_types_param();

}  // namespace pdyn
