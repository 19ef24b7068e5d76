// pdyn/types.hpp — the numeric types every pdyn header uses.
//
// All quantities are SI: metres, seconds, kilograms, newtons. Particle ids
// are dense indices 0..N-1 in the order the scene declares the particles.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>

namespace pdyn {

/// A particle index: 0..N-1, in scene declaration order.
using Index = std::int64_t;

/// A 3-vector (position in m, velocity in m/s, force in N, ...).
using Vec3 = Eigen::Vector3d;

/// Per-particle 3-vectors stored as columns: column i belongs to particle i.
/// Structure of arrays: x, y, z of one particle are adjacent, particles follow
/// each other, so a loop over particles streams memory once.
using Matrix3X = Eigen::Matrix<double, 3, Eigen::Dynamic>;

/// A pair of particle indices (a binary spring's ends).
using IndexPair = std::array<Index, 2>;

/// A triple of particle indices (an angle or area spring's corners).
using IndexTriple = std::array<Index, 3>;

/// A quadruple of particle indices (a dihedral's four corners).
using IndexQuad = std::array<Index, 4>;

}  // namespace pdyn
