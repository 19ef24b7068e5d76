// pdyn/host/decomposition.hpp — cutting one scene's box among MPI ranks
// (issue 43; docs/parallel.md): which rank owns a particle, and which
// other ranks need a ghost copy of it.
//
// The region is cut into a grid of n[0] x n[1] x n[2] boxes (subdomains),
// one per rank, as LAMMPS's `processors` cuts its box (Plimpton, J. Comp.
// Phys. 117, 1, 1995, the spatial decomposition): along a periodic axis
// the region is the box, along an open one the particles' bounds when the
// decomposition is made. Rank r sits at grid cell (r % n0, (r / n0) % n1,
// r / (n0 n1)), x fastest, as in LAMMPS's default `map cart`-less order.
//
// A rank owns the particles whose position lies in its subdomain (a
// particle beyond an open axis's bounds belongs to the outermost cell), and
// holds a ghost copy of every particle within `reach` = cutoff + skin of
// it, its distance to the subdomain measured to the nearest image along
// periodic axes. Between two decompositions no particle moves more than
// skin / 2 (the neighbor lists' rule), so every pair closer than the cutoff
// at any time has an owned particle and a partner that are on the same rank:
// the partner was within cutoff + skin of the owner's subdomain when the
// ghosts were chosen. Pure geometry, no MPI: every rank computes the same
// answers from the same numbers.
#pragma once

#include <array>
#include <pdyn/types.hpp>
#include <string>
#include <utility>
#include <vector>

#include "pdyn/host/export.hpp"

namespace pdyn {

/// How many subdomains along each axis: n[0] n[1] n[2] ranks.
struct PDYN_HOST_API RankGrid {
  std::array<int, 3> n{1, 1, 1};
  int ranks() const noexcept { return n[0] * n[1] * n[2]; }
};

/// LAMMPS's automatic grid (`processors * * *`): of the factorisations
/// n0 n1 n2 = ranks, the one whose subdomains of a region with edge lengths
/// `lengths` (m, each > 0) have the least surface area, the faces ghosts are
/// sent across; ties go to the one cut more along x, then y. Throws Error
/// unless ranks >= 1.
PDYN_HOST_API RankGrid choose_rank_grid(int ranks, const Vec3& lengths);

/// Reads a grid given as "NX,NY,NZ" or "NXxNYxNZ" (pdyn run --grid), each a
/// positive integer, with `ranks` their product. Throws Error naming what
/// is wrong.
PDYN_HOST_API RankGrid parse_rank_grid(const std::string& text, int ranks);

class PDYN_HOST_API Decomposition {
 public:
  /// `lo`, `hi`: the region cut, m (lo < hi along every axis); `periodic`:
  /// which axes wrap (the box's); `reach`: the ghost distance, m (>= 0).
  /// Throws Error when the grid, region or reach is out of range.
  Decomposition(const RankGrid& grid, const Vec3& lo, const Vec3& hi,
                const std::array<bool, 3>& periodic, double reach);

  const RankGrid& grid() const noexcept { return grid_; }
  double reach() const noexcept { return reach_; }
  /// The rank that owns a particle at `x` (m; inside the box along periodic
  /// axes, as a System keeps positions). A non-finite coordinate counts as
  /// the region's lower edge.
  int owner(const Vec3& x) const noexcept;
  /// Appends to `out`, in increasing order, every rank other than `owner`
  /// whose subdomain lies within reach of `x` (nearest image along periodic
  /// axes): the ranks that need a ghost copy of the particle.
  void ghost_ranks(const Vec3& x, int owner, std::vector<int>& out) const;
  /// Subdomain of `rank`: its lower and upper corners, m. Along an open axis
  /// the first and last cells reach to -inf and +inf: a particle that left
  /// the region is owned by the edge cell, and ghost_ranks() measures to it
  /// there.
  std::array<Vec3, 2> bounds(int rank) const;

 private:
  // The position of the k-th cut plane along `axis`, m (k = 0 .. n).
  double plane(int axis, int k) const noexcept;
  // Cell along `axis` holding coordinate c.
  int cell(int axis, double c) const noexcept;
  // Cell k's slab along `axis`, m: the planes, unbounded at an open axis's ends.
  std::pair<double, double> slab(int axis, int k) const noexcept;
  // Distance (m) along `axis` from coordinate c to cell k's slab, nearest image.
  double gap(int axis, double c, int k) const noexcept;

  RankGrid grid_;
  Vec3 lo_, hi_;
  std::array<bool, 3> periodic_{};
  double reach_ = 0.0;
};

}  // namespace pdyn
