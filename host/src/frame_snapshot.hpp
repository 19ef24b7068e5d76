// A copy of one output frame: what lets a writer write a frame on the output
// thread while the solver steps on (the runner's Output), and what carries a
// frame that a failed writer could not write (a full disk) in the checkpoint,
// so that the resumed run writes it first and its output ends up as an
// uninterrupted run's.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "pdyn/domain.hpp"
#include "pdyn/system.hpp"
#include "pdyn/types.hpp"
#include "pdyn/writer.hpp"

namespace pdyn {

class Solver;

struct FrameSnapshot {
  std::int64_t step = 0;  ///< the step the frame belongs to (Frame::step)
  double t = 0.0;         ///< s
  Matrix3X x, v;          ///< m, m/s (3 x N)
  Eigen::VectorXd mass;   ///< kg (N)
  std::vector<std::uint8_t> fixed;
  Domain domain;
  std::vector<double> radius;      ///< m (N) or empty
  std::vector<std::int32_t> type;  ///< N or empty
  std::vector<std::array<std::int32_t, 3>> images;
  bool has_force = false;
  Matrix3X force;                                       ///< N (3 x N), when has_force
  double kinetic_energy = 0.0, potential_energy = 0.0;  ///< J, when asked for
  double virial = 0.0;            ///< J, when asked for (NaN: virial_missing has none)
  std::string virial_missing;     ///< the first force without a virial
  double reservoir_energy = 0.0;  ///< J, when asked for
  double constraint_dof = 0.0;    ///< Frame::constraint_dof, when asked for
  double bonded_energy = 0.0;     ///< Frame::bonded_energy, J, when asked for

  /// Copies the System's current state as the frame of `step`, with its total
  /// forces (the caller has computed them) and energies, virial and the
  /// thermostats' energy (`solver`'s included, if not null) when asked for.
  /// With constraints, the virial includes their forces' for a next step of
  /// `h` (pdyn/thermo.hpp; the caller has evaluated the forces at this
  /// state) and constraint_dof is counted. Once the buffers have their size,
  /// it allocates nothing (without constraints). Without
  /// `with_constraint_virial` (no writer reads the pressure) the constraint
  /// forces' part is not computed: a RATTLE solve per frame saved, and the
  /// virial is NaN with virial_missing saying so.
  void capture(const System& sys, const Solver* solver, std::int64_t step, bool with_force,
               bool with_energy, double h = 0.0, bool with_constraint_virial = true);
  /// The frame a writer is handed, viewing this snapshot: the forces and
  /// energies only where `force` / `energy` (what the writer asked for).
  Frame frame(bool force, bool energy) const;

  /// Bytes for a checkpoint (native byte order, like the checkpoint itself).
  std::vector<std::uint8_t> encode() const;
  /// Reads encode()'s bytes; throws pdyn::Error saying what is malformed.
  static FrameSnapshot decode(std::span<const std::uint8_t> data);
};

}  // namespace pdyn
