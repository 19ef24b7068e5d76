// pdyn/bonded.hpp — bonded terms: the author writes one term, the kernel
// runs the loop. The whole bonded SDK in one include.
//
// A bonded term acts on a fixed list of 2, 3 or 4 particles: a spring
// (bond), a bending angle, a triangle's area, a dihedral. What differs
// between them is one small function of those particles; the loop over the
// terms, the per-type coefficients, the rest values a scene may leave out,
// the threads, the energy and the Jacobians are the same for all. As LAMMPS's
// bond, angle and dihedral styles are, but written once: a plugin supplies a
// *law* and instantiates BondedForce<Law>. Its parts, one header each:
//
//   pdyn/bonded_law.hpp        what a law is: one term's energy (J), forces
//                              (N) and optional Jacobians; BondedPoint,
//                              BondedTerm, BondedMatrix
//   pdyn/bonded_force.hpp      BondedForce<Law>: the loop, its threads and
//                              determinism, energy, virial and Jacobians
//   pdyn/bonded_params.hpp     read_bonded(), bonded_coefficient(),
//                              bonded_types_param(): the parameters every
//                              bonded plugin shares
//   pdyn/bonded_reference.hpp  BondedReference: one term at a time, for the
//                              conformance kit's bonded.* checks
//   pdyn/harmonic.hpp          Harmonic<Geometry>: the damped harmonic law on
//                              a coordinate the author writes once (Coordinate,
//                              Vector3, value_of), Jacobians by Eigen's
//                              automatic differentiation; make_harmonic()
//
// This header includes them all, as it held them all until 0.9.0, so that
// plugin sources written against it compile unchanged. A plugin that writes
// its law by hand and wants no automatic differentiation compiled in
// includes pdyn/bonded_force.hpp instead (spring does).
#pragma once

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <concepts>
#include <cstdint>
#include <limits>
#include <memory>
#include <numbers>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <unsupported/Eigen/AutoDiff>
#include <utility>
#include <vector>

#include "pdyn/bonded_force.hpp"
#include "pdyn/bonded_law.hpp"
#include "pdyn/bonded_params.hpp"
#include "pdyn/bonded_reference.hpp"
#include "pdyn/error.hpp"
#include "pdyn/export.hpp"
#include "pdyn/force.hpp"
#include "pdyn/harmonic.hpp"
#include "pdyn/parallel.hpp"
#include "pdyn/params.hpp"
#include "pdyn/plugin.hpp"
#include "pdyn/thermo.hpp"
