// The anchor of pdyn/bonded_reference.hpp's interface: its destructor, its
// one out-of-line member, so that its vtable and type information are
// emitted once, in the kernel library, rather than in every plugin.
#include "pdyn/bonded_reference.hpp"

namespace pdyn {

BondedReference::~BondedReference() = default;

}  // namespace pdyn
