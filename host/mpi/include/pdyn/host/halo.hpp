// pdyn/host/halo.hpp — the particles of one rank under MPI (issue 43;
// docs/parallel.md): the ones it owns and ghost copies of their neighbors'.
//
// A rank's System holds its owned particles and its ghosts together, sorted
// by global id (a particle's index in the same scene run by one process).
// That order is what keeps a decomposed run bit-identical to the plain one:
// every force sums a particle's terms in increasing partner index
// (pdyn/pair.hpp: each neighbor row is sorted by index; pdyn/parallel.hpp),
// and with local indices in global-id order the increasing local order is
// the plain run's order, the ghosts standing where their particles stand
// there. A ghost's own force is partial and never used; the owned
// particles' forces are the plain run's, bit for bit.
//
// exchange() makes the sets, at the start and whenever a particle would
// otherwise move more than skin / 2 from its place (ParticleRecord::place),
// where the sets were chosen; forward() refreshes the ghosts' positions and velocities from their
// owners before every force evaluation in between, LAMMPS's forward
// communication (Plimpton 1995). Both are MPI_Alltoallv over the
// communicator, each rank sending only to the ranks its particles are
// ghosts on.
#pragma once

#include <mpi.h>

#include <array>
#include <cstdint>
#include <pdyn/types.hpp>
#include <utility>
#include <vector>

#include "pdyn/host/decomposition.hpp"
#include "pdyn/host/export.hpp"

namespace pdyn {

/// One particle as it travels between ranks: everything a System keeps per
/// particle.
struct ParticleRecord {
  std::int64_t id = 0;        ///< global index: the particle's index in the plain run
  std::array<double, 3> x{};  ///< position, m
  std::array<double, 3> v{};  ///< velocity, m/s
  /// Where exchange() places the particle (m, in the box along periodic
  /// axes): its position at the coming force evaluation where a solver's
  /// drift tells it in advance (velocity Verlet's x + h v + h^2 a / 2), else
  /// x. Owners and ghosts are chosen by it, and the particles' moves are
  /// counted from it until the next exchange.
  std::array<double, 3> place{};
  /// The acceleration (m/s^2) a solver that reuses its end-of-step forces
  /// keeps for the next step (pdyn/force_reuse.hpp), carried across an
  /// exchange so that the step after it reuses what the plain run reuses.
  std::array<double, 3> a{};
  double mass = 0.0;    ///< kg
  double radius = 0.0;  ///< m
  std::int32_t type = 0;
  std::array<std::int32_t, 3> images{};
  std::uint8_t fixed = 0;
};

class PDYN_HOST_API Halo {
 public:
  /// `comm`: the ranks sharing the scene, as many as `decomposition`'s grid
  /// has cells (Error otherwise). The communicator is used, not duplicated.
  Halo(MPI_Comm comm, Decomposition decomposition);
  ~Halo();
  Halo(const Halo&) = delete;
  Halo& operator=(const Halo&) = delete;

  /// Makes this rank's particle sets from `held`, whatever particles it
  /// holds now (after a step, its owned ones of the last exchange; at the
  /// start, any share; across the ranks each particle exactly once): every
  /// particle goes to the rank owning its position, and a ghost copy to each
  /// rank within reach. Collective.
  void exchange(const std::vector<ParticleRecord>& held);

  /// Owned particles and ghosts, by increasing id: the local System's order.
  const std::vector<ParticleRecord>& local() const noexcept { return local_; }
  /// Per local() entry: 1 for a ghost, 0 for an owned particle.
  const std::vector<std::uint8_t>& ghost() const noexcept { return ghost_; }
  /// Number of owned particles among local().
  Index owned() const noexcept { return owned_; }

  /// Writes each ghost's position and velocity (columns of `x` and `v`, 3 x
  /// local().size(), in local() order) from its owner's current columns.
  /// Collective; sends 48 bytes per ghost copy.
  void forward(Eigen::Ref<Matrix3X> x, Eigen::Ref<Matrix3X> v) const;

  /// The MPI datatype of one ParticleRecord (its bytes), committed.
  MPI_Datatype record_type() const noexcept { return record_type_; }
  const Decomposition& decomposition() const noexcept { return decomposition_; }
  int rank() const noexcept { return rank_; }
  int ranks() const noexcept { return ranks_; }
  /// Ghost copies this rank sends at each forward() (its halo's size).
  Index ghosts_sent() const noexcept { return static_cast<Index>(send_local_.size()); }

 private:
  // exchange()'s steps: the migration into owned_scratch_ (sorted by id),
  // then the ghost copies sent (to[r]: the owned indices sent to rank r) and
  // received into in_scratch_, returning how many came from each rank.
  void migrate(const std::vector<ParticleRecord>& held);
  std::vector<int> send_ghosts(std::vector<std::vector<std::size_t>>& to);
  // Sends `out` (grouped by destination rank, `count[r]` records for rank r)
  // and puts what arrives into `in`, grouped by source rank (in_count[r]
  // records from rank r).
  void alltoall(const std::vector<ParticleRecord>& out, const std::vector<int>& count,
                std::vector<int>& in_count, std::vector<ParticleRecord>& in) const;

  MPI_Comm comm_;
  MPI_Datatype record_type_ = MPI_DATATYPE_NULL;
  int rank_ = 0, ranks_ = 1;
  Decomposition decomposition_;
  std::vector<ParticleRecord> local_;
  std::vector<std::uint8_t> ghost_;
  Index owned_ = 0;
  // forward(): the local columns sent, grouped by destination rank, and the
  // local columns the arriving ghosts fill, in arrival order; counts and
  // displacements in doubles (6 per particle).
  std::vector<Index> send_local_, recv_local_;
  std::vector<int> send_count_, send_offset_, recv_count_, recv_offset_;
  mutable std::vector<double> send_buffer_, recv_buffer_;
  // exchange()'s buffers, kept for their memory between calls.
  std::vector<ParticleRecord> owned_scratch_, out_scratch_, in_scratch_;
  std::vector<std::pair<std::int64_t, std::int64_t>> order_scratch_;
};

}  // namespace pdyn
