// The parameters every bonded plugin shares: the non-template parts of
// pdyn/bonded_params.hpp.
#include "pdyn/bonded_params.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace pdyn {

std::int32_t bonded_type_count(const Params& params, std::initializer_list<std::string_view> keys) {
  std::size_t n = 1;
  for (const auto key : keys) {
    if (params.has(key)) n = std::max(n, params.reals(key).size());
  }
  for (const auto key : keys) {
    if (!params.has(key)) continue;
    const std::size_t given = params.reals(key).size();
    if (given != 1 && given != n) {
      throw ParamError(std::string(key),
                       fmt::format("has {} values (expected 1 value for all term types, or {}, "
                                   "one per type, as the longest coefficient list gives)",
                                   given, n));
    }
  }
  return static_cast<std::int32_t>(n);
}

double bonded_coefficient(const Params& params, std::string_view key, std::int32_t t) {
  const auto& values = params.reals(key);
  return values.size() == 1 ? values[0] : values.at(static_cast<std::size_t>(t));
}

ParamSpec bonded_types_param() {
  return param::optional("types", ParamType::IntegerList, "",
                         "the type of each term, 0..T-1, choosing its coefficients (one for "
                         "all terms or one per term); default: type 0 for all")
      .at_least(0);
}

}  // namespace pdyn
