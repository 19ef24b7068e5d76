// The atoms a LAMMPS input script makes itself (`lattice`, `region ID block`,
// `create_box`, `create_atoms`) and the velocities `velocity create` gives
// them, bit for bit as LAMMPS (29 Sep 2021, Debian 12) computes them on one
// process: what `pdyn convert` writes to the data file beside the scene.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "pdyn/types.hpp"

namespace pdyn::lammps {

/// The basis of cubic lattice `style` (sc, bcc, fcc) in cell units, in
/// LAMMPS's order (Lattice::Lattice); empty for another style.
std::vector<Vec3> lattice_basis(const std::string& style);

/// The cubic cell's side for reduced density `rho` in lj units:
/// (nbasis / rho)^(1/3), computed as LAMMPS's Lattice does (pow of
/// nbasis / volume / rho with the unit cell's volume 1).
double lattice_spacing(std::size_t nbasis, double rho);

/// An axis-aligned block, lo and hi per axis.
struct Block {
  std::array<double, 3> lo{}, hi{};
};

/// `create_atoms TYPE box` (region == nullptr) or `... region ID`: the
/// lattice sites (i + b) a, in LAMMPS's creation order (z cells outermost,
/// then y, then x, then the basis), that lie in the periodic box shrunk as
/// LAMMPS shrinks it so that no site is made twice across a face: [lo - e,
/// hi - 2 e) per axis, e = 1e-6 of the box's length (CreateAtoms); and, if
/// given, in `region` (bounds included, RegBlock::inside).
std::vector<Vec3> lattice_sites(const std::vector<Vec3>& basis, double spacing, const Block& box,
                                const Block* region);

/// LAMMPS's Park-Miller minimal standard generator (RanPark).
class ParkMiller {
 public:
  explicit ParkMiller(int seed) : seed_(seed) {}
  /// In (0, 1): seed = 16807 seed mod (2^31 - 1) by Schrage's method.
  double uniform();
  /// Standard normal by the polar Box-Muller method, second of each pair
  /// saved.
  double gaussian();
  /// Reseeds from `ibase` and a position (RanPark::reset(int, double*)):
  /// Jenkins's one-at-a-time hash of their bytes, read as signed chars as
  /// LAMMPS reads them, kept to 27 bits, then 5 numbers drawn and dropped.
  void reset(int ibase, const std::array<double, 3>& coord);

 private:
  int seed_;
  bool saved_ = false;
  double second_ = 0.0;
};

/// `velocity GROUP create T SEED` with its keywords: how the numbers are
/// drawn and what is done with them.
struct VelocityCreate {
  enum class Loop { All, Local, Geom };
  double temperature = 0.0;  ///< T, reduced
  int seed = 1;              ///< > 0
  Loop loop = Loop::All;
  bool gaussian = false;  ///< dist gaussian (default uniform)
  bool momentum = true;   ///< mom yes: subtract the centre-of-mass velocity
};

/// The velocities LAMMPS gives atoms with ids 1..n (columns of x, in id
/// order) and masses `mass`, all of them in the group: per atom u - 1/2 (or
/// a normal number) per axis over sqrt(m); the centre-of-mass velocity
/// subtracted; scaled by sqrt(T / T_now) with T_now = sum m v^2 / (3 n - 3)
/// summed in id order (ComputeTemp with its extra 3 degrees of freedom).
/// Throws pdyn::Error when there are no degrees of freedom or T_now is 0.
Matrix3X velocity_create(const Matrix3X& x, const std::vector<double>& mass,
                         const VelocityCreate& c);

}  // namespace pdyn::lammps
