// pdyn/host/decomposed.hpp — one loaded scene run by several MPI ranks
// (issue 43; docs/parallel.md), each stepping its own subdomain.
//
// Every rank loads the scene; DecomposedSystem then replaces the particles
// of the rank's System by its owned particles and their ghosts (Halo), and
// puts a halo object first in the force list, which refreshes the ghosts
// from their owners at every force evaluation before any force reads them.
// The solver steps the local System as it would the whole one: the owned
// particles' forces, and so their steps, are the plain run's bit for bit
// (pdyn/host/halo.hpp). Before each step that would take some owned
// particle (on any rank) more than half the neighbor lists' skin from where
// the last exchange placed it, the particles are exchanged again: migrated
// to their new owners and the ghosts chosen anew.
//
// What runs decomposed so far: pair forces (PairForce<Law>, any plugin, no
// selection), gravity, drag and field, the colliders built on
// SurfaceCollider (box, plane, sphere), and the fixed-step solvers that
// read no global sum (verlet, symplectic_euler, euler, midpoint, rk4).
// Anything else is refused, naming the object and what would make it run.
#pragma once

#include <mpi.h>

#include <array>
#include <cstdint>
#include <iosfwd>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "pdyn/host/halo.hpp"
#include "pdyn/host/runner.hpp"
#include "pdyn/host/scene.hpp"

namespace pdyn {

/// Why a scene cannot run decomposed: what() names the plugin object (its
/// label) and what would make it run.
class PDYN_HOST_API DecompositionError : public Error {
 public:
  using Error::Error;
};

class PDYN_HOST_API DecomposedSystem {
 public:
  /// `scene`: loaded on every rank of `comm`, all particles. Collective.
  /// `grid`: the ranks' grid, or choose_rank_grid's. Throws
  /// DecompositionError when the scene holds what cannot run decomposed yet.
  DecomposedSystem(MPI_Comm comm, Scene& scene, std::optional<RankGrid> grid = std::nullopt);
  ~DecomposedSystem();
  DecomposedSystem(const DecomposedSystem&) = delete;
  DecomposedSystem& operator=(const DecomposedSystem&) = delete;

  /// Call before each step (collective): the ranks agree whether to stop
  /// (some rank's `stop`; it then returns false and does nothing else) and
  /// exchange the particles again when the step would take one more than
  /// skin / 2 from where the last exchange placed it.
  bool begin_step(bool stop = false);

  /// Every particle's position, velocity and image counts, by global id, on
  /// rank `root` (3 x N, N; the other ranks' arguments are left alone).
  /// Collective.
  void gather(int root, Matrix3X& x, Matrix3X& v,
              std::vector<std::array<std::int32_t, 3>>& images) const;
  /// The same into rank 0's copy of the whole scene `whole` (the same scene
  /// loaded there): positions, velocities, image counts, the time, and the
  /// accelerations a solver that reuses its forces keeps (restored into
  /// whole's solver, so that a checkpoint written from it carries them).
  /// Collective; the other ranks' `whole` is not touched.
  void gather_into(Scene& whole) const;

  /// Called by the halo object at every force evaluation, after the
  /// forward: records a violation() when an owned particle is more than
  /// half the skin from where the last exchange placed it, where the ghosts
  /// chosen then may no longer hold all of its partners.
  void check_reach(const ParticleView& p);
  /// What made the last steps' forces unsafe (check_reach), or "".
  const std::string& violation() const noexcept { return violation_; }

  /// This rank's share of the energy check's sums (RankDriver::end_step),
  /// J: its owned particles' kinetic energy plus its forces' potential
  /// energies on its particles, and the same with |U_i|.
  std::array<double, 2> local_energy() const;

  /// The scene stepped on this rank.
  Scene& scene() noexcept { return scene_; }
  const Halo& halo() const noexcept { return *halo_; }
  /// Exchanges so far, the first included.
  std::int64_t exchanges() const noexcept { return exchanges_; }
  /// Total number of particles, on every rank.
  Index particles() const noexcept { return total_; }

 private:
  void load_local();
  // Whether the coming step could take an owned particle of this rank more
  // than skin / 2 from where it was at the last exchange.
  bool exchange_due() const;
  // The accelerations the solver keeps for its next step
  // (pdyn/force_reuse.hpp), or nullptr.
  const Matrix3X* kept_accelerations() const;
  // The owned particles' records; with `place_ahead`, placed where velocity
  // Verlet's drift will take them (ParticleRecord::place) when it is known.
  std::vector<ParticleRecord> owned_records(bool place_ahead) const;
  // The accelerations of velocity Verlet's next drift (its kept ones), when
  // the solver is verlet and keeps them; else nullptr.
  const Matrix3X* drift_accelerations() const;
  std::vector<ParticleRecord> gathered(int root) const;

  MPI_Comm comm_;
  Scene& scene_;
  std::unique_ptr<Halo> halo_;
  std::shared_ptr<Force> halo_force_;
  double half_skin_ = 0.0;
  Matrix3X placed_;           // where the last exchange placed the particles (local order)
  std::vector<Index> owned_;  // the owned particles' local indices, ascending
  bool radii_ = false, types_ = false;
  mutable bool kept_ = false;  // the last owned_records() found kept accelerations
  std::string violation_;
  Index total_ = 0;
  std::int64_t exchanges_ = 0;
};

/// Rank 0's RankDriver (pdyn/host/runner.hpp) on a DecomposedSystem; the
/// other ranks call follow_run with theirs.
class PDYN_HOST_API MpiRankDriver final : public RankDriver {
 public:
  explicit MpiRankDriver(DecomposedSystem& decomposed) : d_(decomposed) {}
  Scene& local() override { return d_.scene(); }
  bool begin_step() override { return d_.begin_step(false); }
  int end_step(Scene& whole, bool gather, bool failed, std::array<double, 2>* energy) override;
  void finish() override { d_.begin_step(true); }

 private:
  DecomposedSystem& d_;
};

/// What a rank other than 0 does while rank 0 runs run_scene with an
/// MpiRankDriver: the same set-up, steps and collectives on its share,
/// until rank 0 finishes. `k0`: the steps taken before (a resumed
/// checkpoint's). `threads` as RunOptions::threads. A failed step
/// is reported on `err`, prefixed with the rank. Returns the rank's exit
/// status: 0, or 4 if one of its steps failed.
PDYN_HOST_API int follow_run(DecomposedSystem& decomposed, std::int64_t k0, int threads,
                             std::ostream& err);

}  // namespace pdyn
