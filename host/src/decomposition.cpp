// The box cut among ranks (pdyn/host/decomposition.hpp).
#include "pdyn/host/decomposition.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <tuple>

#include "pdyn/error.hpp"

namespace pdyn {

RankGrid choose_rank_grid(int ranks, const Vec3& lengths) {
  if (ranks < 1) throw Error(fmt::format("{} ranks: no grid (expected at least 1)", ranks));
  for (int k = 0; k < 3; ++k) {
    if (!(lengths[k] > 0.0 && std::isfinite(lengths[k]))) {
      throw Error(
          fmt::format("region edge {} m along axis {}: no grid (expected > 0)", lengths[k], k));
    }
  }
  RankGrid best;
  double best_area = std::numeric_limits<double>::infinity();
  // Descending, and replaced only by a strictly smaller area: a tie keeps
  // the grid cut more along x, then y.
  for (int n0 = ranks; n0 >= 1; --n0) {
    if (ranks % n0 != 0) continue;
    for (int n1 = ranks / n0; n1 >= 1; --n1) {
      if ((ranks / n0) % n1 != 0) continue;
      const int n2 = ranks / n0 / n1;
      const double a = lengths[0] / n0, b = lengths[1] / n1, c = lengths[2] / n2;
      const double area = a * b + b * c + c * a;
      if (area < best_area * (1.0 - 1e-12)) {
        best_area = area;
        best.n = {n0, n1, n2};
      }
    }
  }
  return best;
}

RankGrid parse_rank_grid(const std::string& text, int ranks) {
  RankGrid grid;
  const char* p = text.data();
  const char* end = p + text.size();
  for (int k = 0; k < 3; ++k) {
    const auto [next, ec] = std::from_chars(p, end, grid.n[k]);
    const bool separated = k == 2 ? next == end : next != end && (*next == ',' || *next == 'x');
    if (ec != std::errc{} || grid.n[k] < 1 || !separated) {
      throw Error(
          fmt::format("--grid {}: not a grid (expected three positive integers, NX,NY,NZ)", text));
    }
    p = next + 1;
  }
  if (grid.ranks() != ranks) {
    throw Error(fmt::format("--grid {}: {} subdomains for {} ranks (expected the product to be {})",
                            text, grid.ranks(), ranks, ranks));
  }
  return grid;
}

Decomposition::Decomposition(const RankGrid& grid, const Vec3& lo, const Vec3& hi,
                             const std::array<bool, 3>& periodic, double reach)
    : grid_(grid), lo_(lo), hi_(hi), periodic_(periodic), reach_(reach) {
  for (int k = 0; k < 3; ++k) {
    if (grid.n[k] < 1)
      throw Error(
          fmt::format("rank grid has {} cells along axis {} (expected >= 1)", grid.n[k], k));
    if (!(lo[k] < hi[k]) || !std::isfinite(lo[k]) || !std::isfinite(hi[k])) {
      throw Error(
          fmt::format("region [{}, {}] m along axis {}: cannot be cut (expected finite, lo < hi)",
                      lo[k], hi[k], k));
    }
  }
  if (!(reach >= 0.0) || !std::isfinite(reach)) {
    throw Error(fmt::format("ghost reach {} m (expected finite, >= 0)", reach));
  }
}

double Decomposition::plane(int axis, int k) const noexcept {
  if (k >= grid_.n[axis]) return hi_[axis];
  return lo_[axis] + (hi_[axis] - lo_[axis]) * k / grid_.n[axis];
}

std::pair<double, double> Decomposition::slab(int axis, int k) const noexcept {
  // Along an open axis the end cells reach to infinity: particles leave the
  // region their first bounds gave, and stay owned by the edge cell (cell()
  // clamps), so ghosts must be measured to where those particles may be.
  const bool open = !periodic_[axis];
  const double inf = std::numeric_limits<double>::infinity();
  return {open && k == 0 ? -inf : plane(axis, k),
          open && k + 1 == grid_.n[axis] ? inf : plane(axis, k + 1)};
}

int Decomposition::cell(int axis, double c) const noexcept {
  const int n = grid_.n[axis];
  if (!(c >= lo_[axis])) return 0;  // below the region, or NaN
  // The cell from the planes themselves, so that ownership and bounds()
  // agree bit for bit: the first k with c < plane(k + 1).
  int k = std::min(n - 1, static_cast<int>((c - lo_[axis]) / (hi_[axis] - lo_[axis]) * n));
  while (k > 0 && c < plane(axis, k)) --k;
  while (k + 1 < n && c >= plane(axis, k + 1)) ++k;
  return k;
}

double Decomposition::gap(int axis, double c, int k) const noexcept {
  const std::pair<double, double> ends = slab(axis, k);
  const double a = ends.first, b = ends.second;
  auto outside = [&](double y) { return y < a ? a - y : (y > b ? y - b : 0.0); };
  double d = outside(c);
  if (periodic_[axis]) {
    const double length = hi_[axis] - lo_[axis];
    d = std::min({d, outside(c - length), outside(c + length)});
  }
  return d;
}

int Decomposition::owner(const Vec3& x) const noexcept {
  return cell(0, x[0]) + grid_.n[0] * (cell(1, x[1]) + grid_.n[1] * cell(2, x[2]));
}

void Decomposition::ghost_ranks(const Vec3& x, int owner, std::vector<int>& out) const {
  // Per axis, the cells within reach and their gaps; a subdomain is within
  // reach when the three gaps' squares sum to less than reach^2 (the
  // distance from a point to a box, each axis's nearest image on its own).
  // A hair of slack makes rounding in the planes err towards a ghost too
  // many, which costs nothing but a copy.
  const double r2 = reach_ * reach_ * (1.0 + 1e-12);
  // Most particles lie deeper than reach inside the owner's subdomain along
  // every cut axis: no other subdomain is nearer than its nearest face.
  const std::array<int, 3> c{cell(0, x[0]), cell(1, x[1]), cell(2, x[2])};
  bool inside = owner == c[0] + grid_.n[0] * (c[1] + grid_.n[1] * c[2]);
  for (int a = 0; a < 3 && inside; ++a) {
    if (grid_.n[a] == 1) continue;
    const auto [lo, hi] = slab(a, c[static_cast<std::size_t>(a)]);
    const double depth = std::min(x[a] - lo, hi - x[a]);
    inside = depth * depth > r2;
  }
  if (inside) return;
  // The per-axis lists, kept between calls (an exchange calls this for
  // every particle near a face).
  thread_local std::array<std::vector<std::pair<int, double>>, 3> near;
  for (int a = 0; a < 3; ++a) {
    near[a].clear();
    for (int k = 0; k < grid_.n[a]; ++k) {
      const double g = gap(a, std::isfinite(x[a]) ? x[a] : lo_[a], k);
      if (g * g <= r2) near[a].emplace_back(k, g * g);
    }
  }
  for (const auto& [k2, g2] : near[2]) {
    for (const auto& [k1, g1] : near[1]) {
      for (const auto& [k0, g0] : near[0]) {
        const int rank = k0 + grid_.n[0] * (k1 + grid_.n[1] * k2);
        if (rank != owner && g0 + g1 + g2 <= r2) out.push_back(rank);
      }
    }
  }
}

std::array<Vec3, 2> Decomposition::bounds(int rank) const {
  const int k0 = rank % grid_.n[0], k1 = (rank / grid_.n[0]) % grid_.n[1],
            k2 = rank / (grid_.n[0] * grid_.n[1]);
  const std::array<int, 3> k{k0, k1, k2};
  std::array<Vec3, 2> b;
  for (int a = 0; a < 3; ++a) std::tie(b[0][a], b[1][a]) = slab(a, k[static_cast<std::size_t>(a)]);
  return b;
}

}  // namespace pdyn
