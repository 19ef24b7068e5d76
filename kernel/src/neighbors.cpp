// The cell list and the Verlet list (see pdyn/neighbors.hpp).
//
// A build has three steps, each O(N):
//
//   1. Grid. Cells of side >= reach / 2 (LAMMPS's default binning; Allen &
//      Tildesley sec. 5.3.2 use side >= reach, which scans 27 cells of
//      volume reach^3, 6.4 times the sphere of reach, where 5 x 5 x 5 cells
//      less the corners that cannot hold a partner scan about 2.5 times it).
//      Along a periodic axis the box is cut into n = floor(2 L / reach)
//      cells; along an open axis the bounding box of the listed particles is,
//      so that the grid follows the particles wherever they go. The total is
//      capped at about 2 N cells by widening every cell, so a sparse system
//      (a galaxy, a few particles in a huge periodic box) costs O(N) memory,
//      not O(volume).
//   2. Counting sort by cell: count per cell, prefix sums, fill. Particles of
//      one cell end up contiguous, ascending by index, with their positions
//      copied next to them (wrapped into the box), so the pair search streams
//      memory instead of gathering it. No per-cell std::vector.
//   3. Pair search, one pass: for each particle i, scan the stencil (the rows
//      of cells along x that can hold a partner, each a contiguous run of
//      the sorted arrays) and keep the j within reach. Along a periodic axis
//      a scanned cell comes with the image shift that brings it next to i's
//      cell, so a distance is three subtractions, no fold, and the keep test
//      is branch-free. Each thread lists its own range of i into its own
//      buffer, rows are sorted, and the buffers are joined in order: row i is
//      computed by the same operations from the same data whatever the
//      split, so the list is bit-identical for every thread count.
//      A half list without a fold scans the stencil's forward half instead
//      (half_pairs, fill_half_rows): each pair once, scattered into the row
//      of its lower index, then the rows sorted: the same rows.
//
// Every buffer is a member that only grows: once warm (a build with the same
// N has run, and the pair count stays within the 1/8 headroom that the
// largest one so far left), neither update() nor build() allocates.
#include "pdyn/neighbors.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <span>
#include <stdexcept>

#include "pdyn/parallel.hpp"

namespace pdyn {
namespace {

// Under MPI ranks a member mask marks a rank's ghosts 2 (set_neighbor_ghosts
// in pdyn/kernel/neighbor_schedule.hpp): a pair of two ghosts gives no owned
// particle a force, and is dropped from the rows, which stay sorted.
void drop_ghost_pairs(const std::vector<std::uint8_t>& mask, std::vector<Index>& offsets,
                      std::vector<Index>& indices) {
  Index kept = 0;
  for (std::size_t i = 0; i + 1 < offsets.size(); ++i) {
    const Index begin = offsets[i], end = offsets[i + 1];
    offsets[i] = kept;
    const bool ghost = mask[i] == 2;
    for (Index k = begin; k < end; ++k) {
      const Index j = indices[static_cast<std::size_t>(k)];
      if (ghost && mask[static_cast<std::size_t>(j)] == 2) continue;
      indices[static_cast<std::size_t>(kept++)] = j;
    }
  }
  offsets.back() = kept;
  indices.resize(static_cast<std::size_t>(kept));
}

// Cells are made this much (relatively) wider than reach, so that rounding
// in a cell index (a few 1e-16 times the number of cells along the axis, in
// cells) can never put two particles closer than reach in cells two apart.
constexpr double kCellMargin = 1e-6;

// The cell cap for n listed particles: 2 n + 1024. More cells than particles
// only adds empty cells to scan; the constant keeps small systems in a large
// periodic box on a grid fine enough to be useful.
double cell_cap(Index n) { return 2.0 * static_cast<double>(n) + 1024.0; }

constexpr char kAxis[3] = {'x', 'y', 'z'};

// Makes room for n elements. The pair count varies from build to build: it
// gets 1/8 headroom when it outgrows the buffer, so that its fluctuations in
// a steady run stop reallocating after the first builds, without the
// doubling of std::vector's own growth.
template <class T>
void reserve_for(std::vector<T>& v, std::size_t n) {
  if (n > v.capacity()) v.reserve(n + n / 8);
}

// Sorts a row ascending. Particles numbered in space (a lattice, a grid, a
// LAMMPS data file, a spatially sorted system) arrive from the stencil
// nearly in order, as the stencil is visited by z, then y, then x: insertion
// sort then does about one comparison per entry, where std::sort's
// partitioning compares each entry log2(count) times with branches that
// mispredict half the time. Insertion sort gives up after 4 moves per entry
// on average (a system numbered at random) and leaves the rest to
// std::sort, so that a row never costs more than about twice its sort.
void sort_row(Index* row, Index count) {
  Index moves = 0;
  const Index budget = 4 * count;
  for (Index k = 1; k < count; ++k) {
    const Index v = row[k];
    Index m = k;
    while (m > 0 && row[m - 1] > v) {
      row[m] = row[m - 1];
      --m;
    }
    row[m] = v;
    moves += k - m;
    if (moves > budget) {
      std::sort(row, row + count);
      return;
    }
  }
}

// A row buffer grown to hold `needed` entries, by half its size at least
// (and 1/8 headroom), so that runs of a build rarely reallocate.
void make_room(std::vector<Index>& buf, std::size_t needed) {
  if (needed > buf.size()) buf.resize(std::max(buf.size() + buf.size() / 2, needed + needed / 8));
}

// The cells [lo, hi] of the x row that starts at cell `base` (nx cells),
// cut at the faces of an open axis or wrapped round a periodic one (of
// `length`): visit(first, last, x shift) for each run of cells.
template <class Visit>
void x_runs(Index base, Index lo, Index hi, Index nx, bool periodic, double length,
            const Visit& visit) {
  if (!periodic) {
    visit(base + std::max<Index>(lo, 0), base + std::min(hi, nx - 1), 0.0);
  } else if (lo < 0) {
    visit(base + lo + nx, base + nx - 1, -length);
    visit(base, base + hi, 0.0);
  } else if (hi >= nx) {
    visit(base + lo, base + nx - 1, 0.0);
    visit(base, base + hi - nx, length);
  } else {
    visit(base + lo, base + hi, 0.0);
  }
}

// A half list's rows from pairs (lower index, higher index) gathered in
// `pairs`, for the rows [first, last) only: count_rows adds each pair's row
// to its size (offsets[row + 1]), scatter_rows writes the higher index at
// its row's cursor (offsets[row], the row's start before, its end after).
// Threads take rows of their own, each reading every thread's pairs: no
// atomics (a chain-numbered melt puts a pair's rows anywhere).
void count_rows(std::span<const Index> pairs, Index first, Index last,
                std::vector<Index>& offsets) {
  for (std::size_t k = 0; k < pairs.size(); k += 2) {
    const Index row = pairs[k];
    if (row >= first && row < last) ++offsets[static_cast<std::size_t>(row) + 1];
  }
}

void scatter_rows(std::span<const Index> pairs, Index first, Index last,
                  std::vector<Index>& offsets, std::vector<Index>& indices) {
  for (std::size_t k = 0; k < pairs.size(); k += 2) {
    const Index row = pairs[k];
    if (row < first || row >= last) continue;
    indices[static_cast<std::size_t>(offsets[static_cast<std::size_t>(row)]++)] = pairs[k + 1];
  }
}

// The squared distance from p to the nearest image of q (Grid::fold), with
// the box's half and whole lengths per axis. Both positions are wrapped, so
// |d| < L: one fold gives the nearest image (half = +inf on open axes: no
// fold). Inlined into fill_row's scan, as written there before.
[[gnu::always_inline]] inline double folded_distance2(const std::array<double, 3>& q,
                                                      const std::array<double, 3>& p,
                                                      const std::array<double, 3>& half,
                                                      const std::array<double, 3>& length) {
  double r2 = 0;
  for (int k = 0; k < 3; ++k) {
    double d = q[k] - p[k];
    if (d > half[k]) {
      d -= length[k];
    } else if (d < -half[k]) {
      d += length[k];
    }
    r2 += d * d;
  }
  return r2;
}

}  // namespace

NeighborList::NeighborList(double cutoff, double skin, Kind kind)
    : cutoff_(cutoff), skin_(skin), kind_(kind) {
  set_range(cutoff, skin);
}

void NeighborList::set_range(double cutoff, double skin) {
  if (!std::isfinite(cutoff) || cutoff <= 0) {
    throw std::invalid_argument(
        fmt::format("neighbor list: cutoff must be finite and > 0 m, got {}", cutoff));
  }
  if (!std::isfinite(skin) || skin < 0) {
    throw std::invalid_argument(
        fmt::format("neighbor list: skin must be finite and >= 0 m, got {}", skin));
  }
  cutoff_ = cutoff;
  skin_ = skin;
  built_ = false;
}

bool NeighborList::update(const Eigen::Ref<const Matrix3X>& x, const Domain& domain,
                          const std::vector<std::uint8_t>* members) {
  return update(x, domain, members, UpdateRule{});
}

bool NeighborList::update(const Eigen::Ref<const Matrix3X>& x, const Domain& domain,
                          const std::vector<std::uint8_t>* members, const UpdateRule& rule) {
  check(x, domain, members);
  const bool resized = rule.box_moved >= 0.0;
  const bool rebuild =
      rule.when == Rebuild::Always ||
      (rule.when == Rebuild::IfForced ? must_rebuild(x, domain, members, resized)
                                      : stale(x, domain, members, resized ? rule.box_moved : -1.0));
  if (!rebuild) return false;
  build(x, domain, members);
  return true;
}

void NeighborList::check(const Eigen::Ref<const Matrix3X>& x, const Domain& domain,
                         const std::vector<std::uint8_t>* members) const {
  for (int k = 0; k < 3; ++k) {
    if (!domain.periodic[k]) continue;
    const double L = domain.max[k] - domain.min[k];
    if (!std::isfinite(L) || L <= 0) {
      throw std::invalid_argument(fmt::format(
          "neighbor list: periodic axis {} needs finite bounds with max > min, got min = {} m, "
          "max = {} m",
          kAxis[k], domain.min[k], domain.max[k]));
    }
    // With L >= 2 reach, a particle has at most one image of each other
    // particle within reach, and the minimum image is that one.
    if (L < 2 * reach()) {
      throw std::invalid_argument(fmt::format(
          "neighbor list: periodic axis {} is {} m long, less than 2 (cutoff + skin) = {} m: a "
          "particle would meet two images of one neighbor",
          kAxis[k], L, 2 * reach()));
    }
  }
  if (members && static_cast<Index>(members->size()) != x.cols()) {
    throw std::invalid_argument(
        fmt::format("neighbor list: the member mask has {} entries for {} particles",
                    members->size(), x.cols()));
  }
}

bool NeighborList::resizes(const Domain& from, const Domain& to) {
  for (int k = 0; k < 3; ++k) {
    if (from.periodic[k] != to.periodic[k]) return false;
    if (!to.periodic[k] && (from.min[k] != to.min[k] || from.max[k] != to.max[k])) return false;
  }
  return true;
}

// A list for other particles, another box (or another kind of box, when a
// resized one may be kept) or another selection.
bool NeighborList::must_rebuild(const Eigen::Ref<const Matrix3X>& x, const Domain& domain,
                                const std::vector<std::uint8_t>* members, bool resized) const {
  if (!built_ || x.cols() != size()) return true;
  if (resized ? !resizes(domain_, domain) : !(domain == domain_)) return true;
  return members ? !std::equal(members->begin(), members->end(), mask_.begin(), mask_.end())
                 : !mask_.empty();
}

// Unused since update() took an UpdateRule; kept because 0.9.0's kernel
// exported it (tests/kernel/kernel_exports.txt): dropping a symbol is an ABI bump.
bool NeighborList::stale(const Eigen::Ref<const Matrix3X>& x, const Domain& domain,
                         const std::vector<std::uint8_t>* members) const {
  return stale(x, domain, members, -1.0);
}

// box_moved < 0: the domain must be the build's; otherwise see UpdateRule.
bool NeighborList::stale(const Eigen::Ref<const Matrix3X>& x, const Domain& domain,
                         const std::vector<std::uint8_t>* members, double box_moved) const {
  const Index n = x.cols();
  if (must_rebuild(x, domain, members, box_moved >= 0.0)) return true;
  // Verlet's criterion: no listed particle has moved more than skin / 2
  // (less the allowance of a resized box, UpdateRule). Particles that were
  // not finite and still are not have no pairs to lose; one that changed
  // between finite and not must be (un)listed.
  const double limit = 0.5 * skin_ - (box_moved > 0.0 ? 2.5 * box_moved : 0.0);
  if (!(limit > 0.0) && skin_ > 0.0) return true;
  const double limit2 = limit * limit;
  std::atomic<bool> moved{false};
  parallel_ranges(n, [&](Index begin, Index end) {
    for (Index i = begin; i < end && !moved.load(std::memory_order_relaxed); ++i) {
      if (!mask_.empty() && !mask_[static_cast<std::size_t>(i)]) continue;
      const Vec3 now = x.col(i);
      const Vec3 then = Eigen::Map<const Vec3>(x0_.data() + 3 * i);
      const bool finite_now = now.allFinite();
      // The nearest image is never further than the raw difference, so its
      // rounding calls are needed only for the few that moved far or wrapped.
      const Vec3 d = now - then;
      if (finite_now != then.allFinite() || (finite_now && d.squaredNorm() > limit2 &&
                                             domain.minimum_image(d).squaredNorm() > limit2)) {
        moved.store(true, std::memory_order_relaxed);
      }
    }
  });
  return moved.load();
}

void NeighborList::build(const Eigen::Ref<const Matrix3X>& x, const Domain& domain,
                         const std::vector<std::uint8_t>* members) {
  check(x, domain, members);
  const Index n = x.cols();
  const auto un = static_cast<std::size_t>(n);

  // The inputs, to tell later whether the list is stale.
  domain_ = domain;
  x0_.resize(3 * un);
  Eigen::Map<Matrix3X>(x0_.data(), 3, n) = x;
  if (members) {
    mask_.assign(members->begin(), members->end());
  } else {
    mask_.clear();
  }

  bin(x, domain);
  make_stencil();
  if (kind_ == Kind::Half && !grid_.fold) {
    fill_half_rows(n);  // drops the pairs of two ghosts as it finds them (half_pairs)
  } else {
    fill_rows(n);
    if (std::find(mask_.begin(), mask_.end(), std::uint8_t{2}) != mask_.end())
      drop_ghost_pairs(mask_, offsets_, indices_);
  }

  built_ = true;
  ++builds_;
  // Stamps are unique in the process: a cache keyed on one can never match
  // another list's build, or a build of this list before set_range().
  static std::atomic<std::uint64_t> last_stamp{0};
  stamp_ = last_stamp.fetch_add(1, std::memory_order_relaxed) + 1;
}

void NeighborList::make_grid(const Domain& domain, const std::array<double, 3>& lo,
                             const std::array<double, 3>& hi, Index listed) {
  // What the grid must cover per axis: the box along periodic axes, the
  // bounding box [lo, hi] of the listed particles along open ones (empty
  // when no particle is listed: lo > hi).
  Grid& g = grid_;
  std::array<double, 3> extent{};
  for (int k = 0; k < 3; ++k) {
    g.periodic[k] = domain.periodic[k];
    if (g.periodic[k]) {
      g.lo[k] = domain.min[k];
      extent[k] = domain.max[k] - domain.min[k];
      g.length[k] = extent[k];
      g.half[k] = 0.5 * extent[k];
    } else {
      g.lo[k] = lo[k] <= hi[k] ? lo[k] : 0.0;
      extent[k] = lo[k] <= hi[k] ? hi[k] - lo[k] : 0.0;
      g.length[k] = 0.0;
      g.half[k] = std::numeric_limits<double>::infinity();  // never fold an open axis
    }
  }

  // Cells per axis: floor(extent / side) with side >= reach / 2 (1 + margin);
  // the side grows until the grid has at most `cap` cells. An extent that
  // overflowed to inf (particles near +-1e308) gets one cell, always right.
  const double cap = cell_cap(listed);
  double side = 0.5 * reach() * (1 + kCellMargin);
  std::array<double, 3> cells{};
  for (;;) {
    double total = 1;
    for (int k = 0; k < 3; ++k) {
      const double e = extent[k] / side;
      cells[k] = std::isfinite(extent[k]) && e >= 2 ? std::min(std::floor(e), cap) : 1.0;
      total *= cells[k];
    }
    if (total <= cap) break;
    side *= std::max(1.25, std::cbrt(total / cap));
  }
  g.fold = false;
  for (int k = 0; k < 3; ++k) {
    g.n[k] = static_cast<Index>(cells[k]);
    g.inv_side[k] = g.n[k] > 1 ? cells[k] / extent[k] : 0.0;
    g.side[k] = g.n[k] > 1 ? extent[k] / cells[k] : 0.0;
    // Two particles within reach have cell coordinates t = (u - lo) / side
    // less than reach / side apart, so floor(t) differs by at most
    // floor(reach / side) + 1 (2 for cells of side > reach / 2).
    g.reach[k] = g.n[k] > 1 ? static_cast<Index>(reach() * g.inv_side[k] * (1 + 1e-12)) + 1 : 1;
    if (g.periodic[k] && g.n[k] < 2 * g.reach[k] + 1) g.fold = true;
  }
}

void NeighborList::make_stencil() {
  const Grid& g = grid_;
  // Per axis and cell coordinate c, what c + o is for |o| <= reach: offsets
  // are visited by increasing |o|, so a cell that two offsets reach (a
  // periodic axis of fewer than 2 reach + 1 cells) is kept for the smaller
  // one only and scanned once; the fold then finds the nearest image.
  for (int k = 0; k < 3; ++k) {
    const Index n = g.n[k], m = g.reach[k];
    edges_[k].fill(Near{});
    for (Index c = 0; c < n; ++c) {
      const Index slot = edge_slot(k, c);
      if (slot < 0) continue;
      Near* row = edges_[static_cast<std::size_t>(k)].data() + slot * kWidth + kMaxReach;
      for (Index a = 0; a <= m; ++a) {
        for (const Index o : {-a, a}) {
          if (a == 0 && o == 0 && row[0].cell >= 0) continue;
          Index u = c + o;
          double shift = 0.0;
          if (g.periodic[k]) {
            if (u < 0) {
              u += n;
              shift = -g.length[k];
            } else if (u >= n) {
              u -= n;
              shift = g.length[k];
            }
          }
          if (u < 0 || u >= n) continue;
          bool seen = false;
          for (Index b = -m; b <= m; ++b) seen = seen || row[b].cell == u;
          if (!seen) row[o] = {u, shift};
        }
      }
    }
  }

  // The rows (dy, dz) whose cells can hold a partner, and how far along x:
  // the gap between cells |d| apart is (|d| - 1) side, taken a little
  // smaller (kCellMargin) so that rounding never drops a cell at exactly
  // reach.
  const auto gap = [&g](int k, Index d) {
    const Index cells_between = std::max<Index>(0, std::abs(d) - 1);
    return static_cast<double>(cells_between) * g.side[k] * (1 - kCellMargin);
  };
  const double reach2 = reach() * reach();
  stencil_rows_ = 0;
  for (Index dz = -g.reach[2]; dz <= g.reach[2]; ++dz) {
    for (Index dy = -g.reach[1]; dy <= g.reach[1]; ++dy) {
      const double rest = reach2 - gap(1, dy) * gap(1, dy) - gap(2, dz) * gap(2, dz);
      if (rest < 0) continue;
      Index half_x = g.reach[0];
      if (g.side[0] > 0) {
        const double cells_x = std::sqrt(rest) / (g.side[0] * (1 - kCellMargin));
        half_x = std::min(half_x, static_cast<Index>(cells_x) + 1);
      }
      stencil_[static_cast<std::size_t>(stencil_rows_++)] = {dy, dz, half_x};
    }
  }
}

// Cells c < m take slots c, cells c >= max(m, n - m) slots 2 m - n + c: two
// cells never share a slot, and there are at most 2 m <= 2 kMaxReach.
Index NeighborList::edge_slot(int k, Index c) const {
  const Index n = grid_.n[k], m = grid_.reach[k];
  if (c < m) return c;
  if (c >= n - m) return 2 * m - n + c;
  return -1;
}

const NeighborList::Near* NeighborList::edge_row(int k, Index c) const {
  const Index slot = edge_slot(k, c);
  if (slot < 0) return nullptr;
  return edges_[static_cast<std::size_t>(k)].data() + slot * kWidth + kMaxReach;
}

void NeighborList::bin(const Eigen::Ref<const Matrix3X>& x, const Domain& domain) {
  const Index n = x.cols();
  const auto un = static_cast<std::size_t>(n);

  // The cell count follows the bounding box of open axes, which changes from
  // build to build (a spreading cloud): room for the most cells N particles
  // can have (16 bytes per cell), so that the grid never reallocates.
  const auto max_cells = static_cast<std::size_t>(cell_cap(n));
  cell_start_.reserve(max_cells + 1);
  cell_fill_.reserve(max_cells);

  // Which particles are listed (members with finite coordinates: cell_of_
  // 0 for now, -1 for the others), and their bounding box.
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::array<double, 3> lo{kInf, kInf, kInf}, hi{-kInf, -kInf, -kInf};
  Index listed = 0;
  cell_of_.resize(un);
  slot_of_.resize(un);
  for (Index i = 0; i < n; ++i) {
    const auto ui = static_cast<std::size_t>(i);
    slot_of_[ui] = -1;
    cell_of_[ui] = -1;
    if ((!mask_.empty() && !mask_[ui]) || !x.col(i).allFinite()) continue;
    cell_of_[ui] = 0;
    ++listed;
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], x(k, i));
      hi[k] = std::max(hi[k], x(k, i));
    }
  }
  make_grid(domain, lo, hi, listed);
  const Grid& g = grid_;

  // The cell of each listed particle, from its position wrapped into the box.
  // Clamped, so that rounding at the top face cannot index past the grid.
  const auto coord = [&g](int k, double u) {
    const double t = (u - g.lo[k]) * g.inv_side[k];
    if (!(t >= 0)) return Index{0};
    return t < static_cast<double>(g.n[k]) ? static_cast<Index>(t) : g.n[k] - 1;
  };
  parallel_ranges(n, [&](Index begin, Index end) {
    for (Index i = begin; i < end; ++i) {
      Index& cell = cell_of_[static_cast<std::size_t>(i)];
      if (cell < 0) continue;
      const Vec3 u = domain.wrap(x.col(i));
      cell = coord(0, u[0]) + g.n[0] * (coord(1, u[1]) + g.n[1] * coord(2, u[2]));
    }
  });

  // Counting sort: particles per cell, prefix sums, then fill in ascending
  // particle order (so each cell's particles are ascending).
  const auto cells = static_cast<std::size_t>(g.n[0] * g.n[1] * g.n[2]);
  cell_start_.assign(cells + 1, 0);
  for (const Index c : cell_of_) {
    if (c >= 0) ++cell_start_[static_cast<std::size_t>(c) + 1];
  }
  for (std::size_t c = 0; c < cells; ++c) cell_start_[c + 1] += cell_start_[c];
  cell_fill_.assign(cell_start_.begin(), cell_start_.end() - 1);
  sorted_index_.resize(static_cast<std::size_t>(listed));
  sorted_pos_.resize(static_cast<std::size_t>(listed));
  for (std::size_t i = 0; i < un; ++i) {
    if (cell_of_[i] < 0) continue;
    const auto s = static_cast<std::size_t>(cell_fill_[static_cast<std::size_t>(cell_of_[i])]++);
    const Vec3 u = domain.wrap(x.col(static_cast<Index>(i)));
    sorted_index_[s] = static_cast<Index>(i);
    sorted_pos_[s] = {u[0], u[1], u[2]};
    slot_of_[i] = static_cast<Index>(s);
  }
}

// Lists the partners of particle i into buf[used, used + count), growing
// buf when a scanned run could overflow it, and returns count: every listed j
// within reach of i (j > i for Kind::Half, j != i for Kind::Full), in stencil
// order. Fold: find the nearest image per pair instead of using the stencil's
// shifts (Grid::fold).
template <bool Fold>
Index NeighborList::fill_row(Index i, std::vector<Index>& buf, Index used) const {
  const Index cell = cell_of_[static_cast<std::size_t>(i)];
  if (cell < 0) return 0;
  const Grid& g = grid_;
  const Point p = sorted_pos_[static_cast<std::size_t>(slot_of_[static_cast<std::size_t>(i)])];
  const Index cx = cell % g.n[0], cy = (cell / g.n[0]) % g.n[1], cz = cell / (g.n[0] * g.n[1]);
  const Near* edge_y = edge_row(1, cy);
  const Near* edge_z = edge_row(2, cz);
  const double reach2 = reach() * reach();
  const bool half = kind_ == Kind::Half;
  const Index* index = sorted_index_.data();
  const Point* pos = sorted_pos_.data();
  Index count = 0;

  // The slots of cells [first, last] of one x row, images shifted by (sx, sy,
  // sz). The candidate is written before the test and kept by advancing
  // count: no branch on the outcome.
  const auto scan = [&](Index first, Index last, double sx, double sy, double sz) {
    const Index begin = cell_start_[static_cast<std::size_t>(first)];
    const Index end = cell_start_[static_cast<std::size_t>(last) + 1];
    make_room(buf, static_cast<std::size_t>(used + count + (end - begin)));
    // A local count: `out` and `count` are both Index, so through the
    // reference every store to out would force a reload of count.
    Index* out = buf.data() + used;
    Index kept = count;
    for (Index s = begin; s < end; ++s) {
      const Index j = index[s];
      const Point& q = pos[s];
      double r2 = 0;
      if constexpr (Fold) {
        r2 = folded_distance2(q, p, g.half, g.length);
      } else {
        const double dx = q[0] + sx - p[0], dy = q[1] + sy - p[1], dz = q[2] + sz - p[2];
        r2 = dx * dx + dy * dy + dz * dz;
      }
      out[kept] = j;
      kept += static_cast<Index>((half ? j > i : j != i) & (r2 <= reach2));
    }
    count = kept;
  };

  const Index nx = g.n[0];
  for (int r = 0; r < stencil_rows_; ++r) {
    const StencilRow& row = stencil_[static_cast<std::size_t>(r)];
    const Near y = edge_y ? edge_y[row.dy] : Near{cy + row.dy, 0.0};
    const Near z = edge_z ? edge_z[row.dz] : Near{cz + row.dz, 0.0};
    if (y.cell < 0 || z.cell < 0) continue;
    const Index base = nx * (y.cell + g.n[1] * z.cell);
    const Index lo = cx - row.half_x, hi = cx + row.half_x;
    if (g.periodic[0] && nx < 2 * row.half_x + 1) {
      scan(base, base + nx - 1, 0.0, y.shift, z.shift);  // the whole row, once (Fold)
    } else {
      x_runs(base, lo, hi, nx, g.periodic[0], g.length[0],
             [&](Index first, Index last, double sx) { scan(first, last, sx, y.shift, z.shift); });
    }
  }
  // Ascending, so that a row depends only on the set of partners (not on
  // the grid), and the force loop walks memory forwards.
  sort_row(buf.data() + used, count);
  return count;
}

void NeighborList::fill_rows(Index n) {
  const auto un = static_cast<std::size_t>(n);
  offsets_.resize(un + 1);
  offsets_[0] = 0;
  int threads = 1;
#ifdef _OPENMP
  if (n >= kParallelMinElements && !omp_in_parallel()) threads = max_threads();
#endif
  if (chunks_.size() + 1 < static_cast<std::size_t>(threads)) chunks_.resize(threads - 1);

  // Lists rows [begin, end) into the buffer of thread t (the list itself for
  // thread 0, so that one thread needs no copy; its whole capacity is room:
  // no allocation once warm) and returns the number of entries.
  const auto row = [this](Index i, std::vector<Index>& buf, Index used) {
    return grid_.fold ? fill_row<true>(i, buf, used) : fill_row<false>(i, buf, used);
  };
  const auto fill = [this, &row](std::size_t t, Index begin, Index end) {
    std::vector<Index>& buf = t == 0 ? indices_ : chunks_[t - 1];
    buf.resize(buf.capacity());
    Index used = 0;
    for (Index i = begin; i < end; ++i) {
      const Index count = row(i, buf, used);
      offsets_[static_cast<std::size_t>(i) + 1] = count;
      used += count;
    }
    return used;
  };
  const auto prefix_sums = [this, un] {
    for (std::size_t i = 0; i < un; ++i) offsets_[i + 1] += offsets_[i];
  };

  // A first build reserves the list from a sample of 1 row in 64 (and 1/4
  // more), so that it does not grow by steps, holding old and new buffers at
  // once (what LAMMPS's "memory allocation" would then count twice).
  if (indices_.capacity() == 0 && n > 0) {
    Index sampled = 0, rows = 0;
    for (Index i = 0; i < n; i += 64, ++rows) {
      sampled += row(i, indices_, 0);
    }
    const double estimate =
        1.25 * static_cast<double>(sampled) * static_cast<double>(n) / static_cast<double>(rows);
    std::vector<Index>().swap(indices_);
    indices_.reserve(static_cast<std::size_t>(estimate) + 1024);
    for (std::size_t t = 1; t < static_cast<std::size_t>(threads); ++t) {
      chunks_[t - 1].reserve(static_cast<std::size_t>(estimate / threads) + 1024);
    }
  }

  if (threads == 1) {
    fill(0, 0, n);
    prefix_sums();
    indices_.resize(static_cast<std::size_t>(offsets_[un]));
    return;
  }
#ifdef _OPENMP
#pragma omp parallel num_threads(threads)
  {
    const Index t = omp_get_thread_num(), nt = omp_get_num_threads();
    const Index begin = n * t / nt, end = n * (t + 1) / nt;
    fill(static_cast<std::size_t>(t), begin, end);
#pragma omp barrier
#pragma omp single
    {
      // Thread 0's rows stay where they are, at the start of the list.
      prefix_sums();
      reserve_for(indices_, static_cast<std::size_t>(offsets_[un]));
      indices_.resize(static_cast<std::size_t>(offsets_[un]));
    }
    if (t > 0) {
      const auto from = chunks_[static_cast<std::size_t>(t) - 1].begin();
      std::copy(from,
                from + (offsets_[static_cast<std::size_t>(end)] -
                        offsets_[static_cast<std::size_t>(begin)]),
                indices_.begin() + offsets_[static_cast<std::size_t>(begin)]);
    }
  }
#endif
}

// The pairs within reach of the particle in `slot`, each pair of the list
// found from one of its two particles only: the later slots of its own cell
// and the cells of the stencil's forward half, rows dz > 0 or dz = 0 and
// dy > 0 whole and row (0, 0) from x offset 1 on (LAMMPS's half/bin/newton
// stencil). Without a fold every cell within reach is one offset away, so
// the other particle finds the pair in its backward half, which it does not
// scan. Written to buf[used, ...) as (lower index, higher index); returns
// the count of entries (twice the pairs). Half the distances of fill_row's
// full stencil, whose rows keep j > i only.
Index NeighborList::half_pairs(Index slot, std::vector<Index>& buf, Index used) const {
  const Grid& g = grid_;
  const auto us = static_cast<std::size_t>(slot);
  const Index i = sorted_index_[us];
  const Index cell = cell_of_[static_cast<std::size_t>(i)];
  const Point p = sorted_pos_[us];
  const Index cx = cell % g.n[0], cy = (cell / g.n[0]) % g.n[1], cz = cell / (g.n[0] * g.n[1]);
  const Near* edge_y = edge_row(1, cy);
  const Near* edge_z = edge_row(2, cz);
  const double reach2 = reach() * reach();
  const Index* index = sorted_index_.data();
  const Point* pos = sorted_pos_.data();
  Index count = 0;
  // A ghost (member mask 2, set_neighbor_ghosts) keeps no pair with another
  // ghost: dropped here, before the rows are counted, scattered and sorted.
  const std::uint8_t* ghost_of =
      !mask_.empty() && mask_[static_cast<std::size_t>(i)] == 2 ? mask_.data() : nullptr;

  // Slots [begin, end) shifted by (sx, sy, sz); the candidate is written
  // before the test and kept by advancing: no branch on the outcome.
  const auto scan = [&](Index begin, Index end, double sx, double sy, double sz) {
    if (begin >= end) return;
    make_room(buf, static_cast<std::size_t>(used + count + 2 * (end - begin)));
    Index* out = buf.data() + used;
    Index kept = count;
    const auto candidates = [&](auto keep) {
      for (Index s = begin; s < end; ++s) {
        const Index j = index[s];
        const Point& q = pos[s];
        const double dx = q[0] + sx - p[0], dy = q[1] + sy - p[1], dz = q[2] + sz - p[2];
        const double r2 = dx * dx + dy * dy + dz * dz;
        out[kept] = std::min(i, j);
        out[kept + 1] = std::max(i, j);
        kept += 2 * static_cast<Index>(keep(r2, j));
      }
    };
    if (ghost_of == nullptr) {
      candidates([&](double r2, Index) { return r2 <= reach2; });
    } else {
      candidates([&](double r2, Index j) { return r2 <= reach2 && ghost_of[j] != 2; });
    }
    count = kept;
  };
  const auto cells = [&](Index first, Index last, double sx, double sy, double sz) {
    if (first > last) return;
    scan(cell_start_[static_cast<std::size_t>(first)],
         cell_start_[static_cast<std::size_t>(last) + 1], sx, sy, sz);
  };

  scan(slot + 1, cell_start_[static_cast<std::size_t>(cell) + 1], 0.0, 0.0, 0.0);
  const Index nx = g.n[0];
  for (int r = 0; r < stencil_rows_; ++r) {
    const StencilRow& row = stencil_[static_cast<std::size_t>(r)];
    if (row.dz < 0 || (row.dz == 0 && row.dy < 0)) continue;
    const Index from = row.dz == 0 && row.dy == 0 ? 1 : -row.half_x;
    if (from > row.half_x) continue;
    const Near y = edge_y ? edge_y[row.dy] : Near{cy + row.dy, 0.0};
    const Near z = edge_z ? edge_z[row.dz] : Near{cz + row.dz, 0.0};
    if (y.cell < 0 || z.cell < 0) continue;
    const Index base = nx * (y.cell + g.n[1] * z.cell);
    const Index lo = cx + from, hi = cx + row.half_x;
    x_runs(base, lo, hi, nx, g.periodic[0], g.length[0],
           [&](Index first, Index last, double sx) { cells(first, last, sx, y.shift, z.shift); });
  }
  return count;
}

// Kind::Half without a fold: the pairs, each found once (half_pairs), over
// slots in cell order (neighbors in memory) and split over the threads;
// then counted per row of the lower index, scattered into the rows and each
// row sorted, so that the list is what fill_row gives: the same rows,
// ascending, whatever the thread count.
void NeighborList::fill_half_rows(Index n) {
  int threads = 1;
#ifdef _OPENMP
  if (n >= kParallelMinElements && !omp_in_parallel()) threads = max_threads();
#endif
  const auto un = static_cast<std::size_t>(n);
  const auto slots = static_cast<Index>(sorted_index_.size());
  if (chunks_.size() < static_cast<std::size_t>(threads)) chunks_.resize(threads);
  offsets_.assign(un + 1, 0);

  // Thread t's pairs, the first used[t] entries of its buffer. The buffers
  // keep their size between builds: shrunk to the pairs and grown back to
  // their capacity, they would be zeroed again at every build (19 MB on the
  // 32,000-atom LJ melt). The counts are the calling thread's, so that a
  // warm build allocates nothing; the OpenMP threads reach them through the
  // reference (named there, a thread_local would be each worker's own).
  thread_local std::vector<std::size_t> counts;
  std::vector<std::size_t>& used = counts;
  used.assign(static_cast<std::size_t>(threads), 0);
  const auto gather = [&](int t, int nt) {
    std::vector<Index>& buf = chunks_[static_cast<std::size_t>(t)];
    if (buf.size() < buf.capacity()) buf.resize(buf.capacity());
    Index count = 0;
    for (Index s = slots * t / nt, end = slots * (t + 1) / nt; s < end; ++s) {
      count += half_pairs(s, buf, count);
    }
    used[static_cast<std::size_t>(t)] = static_cast<std::size_t>(count);
  };
  const auto pairs = [&](int t) {
    return std::span<const Index>(chunks_[static_cast<std::size_t>(t)].data(),
                                  used[static_cast<std::size_t>(t)]);
  };
  const auto starts = [&] {
    for (std::size_t i = 0; i < un; ++i) offsets_[i + 1] += offsets_[i];
    reserve_for(indices_, static_cast<std::size_t>(offsets_[un]));
    indices_.resize(static_cast<std::size_t>(offsets_[un]));
  };
  // After the scatter offsets_[i] is row i's end: one place down, its start.
  const auto restore_starts = [&] {
    for (std::size_t i = un; i > 0; --i) offsets_[i] = offsets_[i - 1];
    offsets_[0] = 0;
  };
  const auto sort_rows = [&](Index begin, Index end) {
    for (Index i = begin; i < end; ++i) {
      const Index first = offsets_[static_cast<std::size_t>(i)];
      sort_row(indices_.data() + first, offsets_[static_cast<std::size_t>(i) + 1] - first);
    }
  };

  if (threads == 1) {
    gather(0, 1);
    count_rows(pairs(0), 0, n, offsets_);
    starts();
    scatter_rows(pairs(0), 0, n, offsets_, indices_);
    restore_starts();
    sort_rows(0, n);
    return;
  }
#ifdef _OPENMP
#pragma omp parallel num_threads(threads)
  {
    const int t = omp_get_thread_num(), nt = omp_get_num_threads();
    const Index first = n * t / nt, last = n * (t + 1) / nt;
    gather(t, nt);
#pragma omp barrier
    for (int u = 0; u < nt; ++u) count_rows(pairs(u), first, last, offsets_);
#pragma omp barrier
#pragma omp single
    starts();
    for (int u = 0; u < nt; ++u) {
      scatter_rows(pairs(u), first, last, offsets_, indices_);
    }
#pragma omp barrier
#pragma omp single
    restore_starts();
    sort_rows(first, last);
  }
#endif
}

}  // namespace pdyn
