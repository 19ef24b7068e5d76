// The anchor of pdyn/force_reuse.hpp's type_info: one for every library, so
// that dynamic_cast finds the interface across plugins.
#include "pdyn/force_reuse.hpp"

namespace pdyn {

ForceReuseHolder::~ForceReuseHolder() = default;

}  // namespace pdyn
