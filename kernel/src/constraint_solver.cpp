// The anchor of pdyn/constraint_solver.hpp's type_info: one for every
// library, so that the host's dynamic_cast finds the interface in a solver.
#include "pdyn/constraint_solver.hpp"

namespace pdyn {

ConstraintSolver::~ConstraintSolver() = default;

}  // namespace pdyn
