// pdyn/kernel/neighbor_schedule.hpp — when the shared neighbor lists of a
// system are rebuilt, counted in steps (LAMMPS's neigh_modify).
//
// A host's setting, not a plugin's: the host that steps a system names each
// step, and the kernel's shared lists (SharedNeighborList, which every
// PairForce uses, also in plugins built before this existed) decide from it.
// It lives outside the plugin SDK's folder for that reason
// (tests/kernel/check_sdk.py).
#pragma once

#include <cstdint>

#include "pdyn/export.hpp"

namespace pdyn {

/// When the shared lists of one system are rebuilt, counted in steps: LAMMPS's
/// `neigh_modify every N delay D check yes|no`. Lists decide once per step,
/// at their first update() in it: when `delay` steps or more have passed
/// since their last build and that count is a multiple of `every`, they
/// rebuild if a particle moved more than skin / 2 (`check`) or always (not
/// `check`); at any other step they keep the list, whatever the particles
/// did. The default (every 1, delay 0, check) is Verlet's rule once per step.
/// Anything else can miss pairs that come within the cutoff between
/// decisions, as LAMMPS does: it exists to reproduce a LAMMPS run, pair for
/// pair.
struct RebuildSchedule {
  std::int64_t every = 1;  ///< steps between decisions (>= 1)
  std::int64_t delay = 0;  ///< steps after a build before the first decision (>= 0)
  bool check = true;       ///< at a decision, rebuild only if some particle moved > skin / 2
  bool operator==(const RebuildSchedule&) const = default;
};

/// A step starting at time t (s) begins for the shared lists on the
/// positions array `x` (the System's own, System::positions().data()),
/// under `schedule`. A step begun again with the same t (a replayed step)
/// is not counted twice. Lists on x that were never given a schedule, or
/// were given the default, keep NeighborList::update()'s rule at every call.
/// Throws std::invalid_argument when every < 1 or delay < 0.
PDYN_API void begin_neighbor_step(const double* x, double t, const RebuildSchedule& schedule);

/// Since 0.10.0, for a host that runs a scene on MPI ranks (pdyn/host/
/// halo.hpp): which of the `n` particles of the system whose positions
/// array is `x` are ghosts, copies of particles another rank owns (`ghost`:
/// n flags, non-zero for a ghost), or none (`ghost` nullptr: forgets `x`).
/// The shared lists on `x` then leave out every pair of two ghosts, which
/// gives no owned particle a force, so that the pair loops skip them; they
/// rebuild at their next update. The flags are copied.
PDYN_API void set_neighbor_ghosts(const double* x, const std::uint8_t* ghost, std::int64_t n);

}  // namespace pdyn
