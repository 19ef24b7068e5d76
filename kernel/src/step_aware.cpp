// The anchor of pdyn/step_aware.hpp's type_info: one for every library,
// so that dynamic_cast finds the interface across plugins.
#include "pdyn/step_aware.hpp"

namespace pdyn {

StepAware::~StepAware() = default;

}  // namespace pdyn
