// The anchor of pdyn/periodic_invariant.hpp's type_info: one for every
// library, so that dynamic_cast finds the interface across plugins.
#include "pdyn/periodic_invariant.hpp"

namespace pdyn {

PeriodicInvariant::~PeriodicInvariant() = default;

}  // namespace pdyn
