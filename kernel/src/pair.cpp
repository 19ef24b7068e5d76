// The out-of-line part of the pair-force SDK: the check that a cutoff fits
// the periodic box, with the message a scene author sees; and the key
// function of PairReference, so that its type information lives once, in
// the kernel, and dynamic_cast finds it from any plugin.
#include "pdyn/pair.hpp"

#include <fmt/format.h>

namespace pdyn {

PairReference::~PairReference() = default;
PairLoop::~PairLoop() = default;
PairRange::~PairRange() = default;

void check_cutoff_fits(const Domain& domain, double cutoff, double skin) {
  const double reach = cutoff + skin;
  for (int k = 0; k < 3; ++k) {
    if (!domain.periodic[k]) continue;
    const double length = domain.max[k] - domain.min[k];
    if (length < 2 * reach) {
      throw ParamError("cutoff", fmt::format("{} m with skin {} m does not fit the periodic box: "
                                             "its {} side is {} m (expected a side of at least "
                                             "2 (cutoff + skin) = {} m)",
                                             cutoff, skin, "xyz"[k], length, 2 * reach));
    }
  }
}

}  // namespace pdyn
