// The key functions of the optional force interfaces MovableTargets
// (pdyn/targets.hpp), LocalForce and LinearLocalForce
// (pdyn/local_force.hpp): their type_info
// lives in the kernel, so a dynamic_cast recognises the interface in a force
// created by any plugin library.
#include "pdyn/targets.hpp"

#include "pdyn/local_force.hpp"

namespace pdyn {

MovableTargets::~MovableTargets() = default;
LocalForce::~LocalForce() = default;
LinearLocalForce::~LinearLocalForce() = default;

}  // namespace pdyn
