// The cell list and the Verlet list (see pdyn/neighbors.hpp).
//
// A build has three steps, each O(N):
//
//   1. Grid. Cells of side >= reach (Allen & Tildesley sec. 5.3.2): along a
//      periodic axis the box is cut into n = floor(L / reach) cells; along an
//      open axis the bounding box of the listed particles is, so that the grid
//      follows the particles wherever they go. The total is capped at about
//      2 N cells by widening every cell, so a sparse system (a galaxy, a few
//      particles in a huge periodic box) costs O(N) memory, not O(volume).
//   2. Counting sort by cell: count per cell, prefix sums, fill. Particles of
//      one cell end up contiguous, ascending by index, with their positions
//      copied next to them (wrapped into the box), so the pair search streams
//      memory instead of gathering it. No per-cell std::vector.
//   3. Pair search, in compressed sparse row form: for each particle i, scan
//      its own and the adjacent cells (27, fewer where an axis has 1 or 2
//      cells) and keep the j within reach. A first pass counts per i, a
//      prefix sum makes the row offsets, a second pass fills and sorts each
//      row. Both passes are split over threads by i (pdyn::parallel_ranges):
//      row i is computed by the same operations from the same data whatever
//      the split, so the list is bit-identical for every thread count.
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
#include <stdexcept>

#include "pdyn/parallel.hpp"

namespace pdyn {
namespace {

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

}  // namespace

NeighborList::NeighborList(double cutoff, double skin, Kind kind)
    : cutoff_(cutoff), skin_(skin), kind_(kind) {
  if (!std::isfinite(cutoff) || cutoff <= 0) {
    throw std::invalid_argument(
        fmt::format("neighbor list: cutoff must be finite and > 0 m, got {}", cutoff));
  }
  if (!std::isfinite(skin) || skin < 0) {
    throw std::invalid_argument(
        fmt::format("neighbor list: skin must be finite and >= 0 m, got {}", skin));
  }
}

bool NeighborList::update(const Eigen::Ref<const Matrix3X>& x, const Domain& domain,
                          const std::vector<std::uint8_t>* members) {
  check(x, domain, members);
  if (!stale(x, domain, members)) return false;
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

bool NeighborList::stale(const Eigen::Ref<const Matrix3X>& x, const Domain& domain,
                         const std::vector<std::uint8_t>* members) const {
  const Index n = x.cols();
  if (!built_ || n != size() || !(domain == domain_)) return true;
  if (members ? !std::equal(members->begin(), members->end(), mask_.begin(), mask_.end())
              : !mask_.empty()) {
    return true;
  }
  // Verlet's criterion: no listed particle has moved more than skin / 2.
  // Particles that were not finite and still are not have no pairs to lose;
  // one that changed between finite and not must be (un)listed.
  const double limit2 = 0.25 * skin_ * skin_;
  std::atomic<bool> moved{false};
  parallel_ranges(n, [&](Index begin, Index end) {
    for (Index i = begin; i < end && !moved.load(std::memory_order_relaxed); ++i) {
      if (!mask_.empty() && !mask_[static_cast<std::size_t>(i)]) continue;
      const Vec3 now = x.col(i);
      const Vec3 then = Eigen::Map<const Vec3>(x0_.data() + 3 * i);
      const bool finite_now = now.allFinite();
      if (finite_now != then.allFinite() ||
          (finite_now && domain.minimum_image(now - then).squaredNorm() > limit2)) {
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

  // Pass 1: the length of every row, into offsets_[i + 1].
  offsets_.resize(un + 1);
  offsets_[0] = 0;
  parallel_ranges(n, [&](Index begin, Index end) {
    for (Index i = begin; i < end; ++i) {
      Index count = 0;
      for_each_partner(i, [&count](Index) { ++count; });
      offsets_[static_cast<std::size_t>(i) + 1] = count;
    }
  });
  for (std::size_t i = 0; i < un; ++i) offsets_[i + 1] += offsets_[i];

  // Pass 2: fill each row, then sort it, so the order of a row depends only
  // on the set of neighbors (not on the grid, the cell scan or the threads).
  reserve_for(indices_, static_cast<std::size_t>(offsets_[un]));
  indices_.resize(static_cast<std::size_t>(offsets_[un]));
  parallel_ranges(n, [&](Index begin, Index end) {
    for (Index i = begin; i < end; ++i) {
      const auto row = indices_.begin() + offsets_[static_cast<std::size_t>(i)];
      auto out = row;
      for_each_partner(i, [&out](Index j) { *out++ = j; });
      std::sort(row, out);
    }
  });

  built_ = true;
  ++builds_;
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

  // Cells per axis: floor(extent / side) with side >= reach (1 + margin); the
  // side grows until the grid has at most `cap` cells. An extent that
  // overflowed to inf (particles near +-1e308) gets one cell, always right.
  const double cap = cell_cap(listed);
  double side = reach() * (1 + kCellMargin);
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
  for (int k = 0; k < 3; ++k) {
    g.n[k] = static_cast<Index>(cells[k]);
    g.inv_side[k] = g.n[k] > 1 ? cells[k] / extent[k] : 0.0;
  }
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

// Calls visit(j) for every listed j within reach of listed particle i (j > i
// for Kind::Half, j != i for Kind::Full), scanning i's own and adjacent cells.
template <class Visit>
void NeighborList::for_each_partner(Index i, Visit&& visit) const {
  const Index cell = cell_of_[static_cast<std::size_t>(i)];
  if (cell < 0) return;
  const Grid& g = grid_;
  const Point& p = sorted_pos_[static_cast<std::size_t>(slot_of_[static_cast<std::size_t>(i)])];
  const std::array<Index, 3> c{cell % g.n[0], (cell / g.n[0]) % g.n[1], cell / (g.n[0] * g.n[1])};

  // The distinct cell coordinates next to c[k] along each axis. A periodic
  // axis of 2 cells has c - 1 == c + 1, and one of 1 cell has only c: each
  // cell is scanned once, so no pair is found twice.
  std::array<std::array<Index, 3>, 3> near{};
  std::array<int, 3> count{};
  for (int k = 0; k < 3; ++k) {
    const Index nk = g.n[k], ck = c[k];
    auto& out = near[k];
    int& m = count[k];
    if (g.periodic[k] && nk >= 3) {
      out = {(ck + nk - 1) % nk, ck, (ck + 1) % nk};
      m = 3;
    } else if (g.periodic[k]) {
      out[m++] = ck;
      if (nk == 2) out[m++] = 1 - ck;
    } else {
      if (ck > 0) out[m++] = ck - 1;
      out[m++] = ck;
      if (ck + 1 < nk) out[m++] = ck + 1;
    }
  }

  const double reach2 = reach() * reach();
  const bool half = kind_ == Kind::Half;
  for (int a = 0; a < count[2]; ++a) {
    for (int b = 0; b < count[1]; ++b) {
      for (int e = 0; e < count[0]; ++e) {
        const auto nc =
            static_cast<std::size_t>(near[0][e] + g.n[0] * (near[1][b] + g.n[1] * near[2][a]));
        const Index* first = sorted_index_.data() + cell_start_[nc];
        const Index* last = sorted_index_.data() + cell_start_[nc + 1];
        // A half list only wants j > i: a cell's particles are ascending.
        if (half) first = std::upper_bound(first, last, i);
        for (const Index* s = first; s < last; ++s) {
          const Index j = *s;
          if (j == i) continue;
          const Point& q = sorted_pos_[static_cast<std::size_t>(s - sorted_index_.data())];
          double r2 = 0;
          for (int k = 0; k < 3; ++k) {
            // Both positions are wrapped, so |d| < L: one fold gives the
            // nearest image (half = +inf on open axes: no fold).
            double d = q[k] - p[k];
            if (d > g.half[k]) {
              d -= g.length[k];
            } else if (d < -g.half[k]) {
              d += g.length[k];
            }
            r2 += d * d;
          }
          if (r2 <= reach2) visit(j);
        }
      }
    }
  }
}

}  // namespace pdyn
