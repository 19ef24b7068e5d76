// Harmonic's coefficients and parameters: the non-template parts of
// pdyn/harmonic.hpp.
#include "pdyn/harmonic.hpp"

namespace pdyn {

std::vector<HarmonicCoefficients> harmonic_coefficients(const Params& params, std::int32_t n_types,
                                                        std::string_view k, std::string_view kd) {
  std::vector<HarmonicCoefficients> out(static_cast<std::size_t>(n_types));
  for (std::int32_t t = 0; t < n_types; ++t) {
    out[static_cast<std::size_t>(t)] = {bonded_coefficient(params, k, t),
                                        bonded_coefficient(params, kd, t)};
  }
  return out;
}

std::vector<ParamSpec> harmonic_params(const std::string& what, const std::string& k_unit,
                                       const std::string& kd_unit) {
  return {bonded_types_param(),
          param::real_list("k", 1.0, k_unit, what + ": one for all term types or one per type")
              .at_least(0),
          param::real_list("kd", 0.0, kd_unit,
                           "damping of its rate: one for all term types or one per type")
              .at_least(0)};
}

}  // namespace pdyn
