// pdyn/host/resolve.hpp — the one place parameter values meet their specs.
//
// Whoever builds a plugin object (the scene loader from YAML, the viewer
// when the user adds a force, the conformance kit, a script) has some
// values already in their types and the descriptor's ParamSpecs. resolve()
// fills every default, and checks that required parameters are given, that
// each value has its declared type, that numbers are finite and within their
// bounds (each element of a vector or list), that a vector declared
// not_zero is not zero, and that every given name is declared. It knows
// nothing of YAML: a reader converts text to values and maps each problem
// back to where the value was written.
#pragma once

#include <string>
#include <vector>

#include "pdyn/host/export.hpp"
#include "pdyn/params.hpp"

namespace pdyn {

/// One problem resolve() found with one parameter.
struct PDYN_HOST_API ParamProblem {
  enum class Kind {
    Missing,     ///< required and not given
    WrongType,   ///< given (or defaulted) as a value of another type
    NotFinite,   ///< a NaN or infinite number
    OutOfRange,  ///< a number outside [min, max] (or not above an exclusive min)
    ZeroVector,  ///< the zero vector where the spec says not_zero
    Unknown,     ///< a name no spec declares
  };
  Kind kind = Kind::Missing;
  std::string param;  ///< the parameter's name
  /// Where inside the value: {} for the whole value, {k} for component k of
  /// a vector or element k of a list, {e, k} for component k of element e of
  /// a vector list.
  std::vector<std::size_t> element;
  std::string key;      ///< NamedReals: the name of the offending entry
  double value = 0.0;   ///< NotFinite, OutOfRange: the offending number
  std::string message;  ///< one line, "what is wrong (what was expected)", without a location
};

/// Values with every default filled in, and what is wrong with them.
struct PDYN_HOST_API Resolved {
  Params params;  ///< every given value (even one with a problem) plus the defaults
  std::vector<ParamProblem> problems;  ///< in spec order; at most one per vector or list element
  bool ok() const noexcept { return problems.empty(); }
};

/// Resolves `given` against `specs`. Never throws for bad values: each is a
/// problem in the result.
PDYN_HOST_API Resolved resolve(const std::vector<ParamSpec>& specs, const Params& given);

/// What a spec accepts, for messages: "a number > 0 in s", "a vector [x, y,
/// z], not zero in m".
PDYN_HOST_API std::string expectation(const ParamSpec& spec);

}  // namespace pdyn
