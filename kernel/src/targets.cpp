// The key function of MovableTargets (pdyn/targets.hpp): its type_info lives
// in the kernel, so a host's dynamic_cast recognises the interface in a
// force created by any plugin library.
#include "pdyn/targets.hpp"

namespace pdyn {

MovableTargets::~MovableTargets() = default;

}  // namespace pdyn
