// The special partners of a bond graph (pdyn/special_bonds.hpp): each
// particle's partners one, two and three bonds away, as LAMMPS's
// Special::build counts them. Its 1-3 partners of i are the bond partners
// of i's bond partners other than i, its 1-4 partners the bond partners of
// those other than i, and a partner found at several depths keeps the
// smallest (Special::combine): that is the graph distance, so a breadth-first
// search to depth 3 from each particle gives the same classes.
#include "pdyn/special_bonds.hpp"

#include <fmt/format.h>

#include <stdexcept>

namespace pdyn {

SpecialBondsTarget::~SpecialBondsTarget() = default;

namespace {

// The bond graph as sorted, repeat-free adjacency rows (CSR).
struct Graph {
  std::vector<Index> offsets, partners;
  std::span<const Index> row(Index i) const {
    const auto b = static_cast<std::size_t>(offsets[static_cast<std::size_t>(i)]);
    const auto e = static_cast<std::size_t>(offsets[static_cast<std::size_t>(i) + 1]);
    return std::span<const Index>(partners).subspan(b, e - b);
  }
};

Graph bond_graph(Index n, std::span<const IndexPair> bonds) {
  std::vector<std::vector<Index>> adj(static_cast<std::size_t>(n));
  for (std::size_t b = 0; b < bonds.size(); ++b) {
    const auto [i, j] = bonds[b];
    if (i < 0 || j < 0 || i >= n || j >= n) {
      throw std::invalid_argument(fmt::format(
          "bond {} joins particles {} and {} (expected indices in 0 .. {})", b, i, j, n - 1));
    }
    if (i == j) {
      throw std::invalid_argument(
          fmt::format("bond {} joins particle {} to itself (expected two particles)", b, i));
    }
    adj[static_cast<std::size_t>(i)].push_back(j);
    adj[static_cast<std::size_t>(j)].push_back(i);
  }
  Graph g;
  g.offsets.reserve(static_cast<std::size_t>(n) + 1);
  g.offsets.push_back(0);
  for (auto& row : adj) {
    std::sort(row.begin(), row.end());
    row.erase(std::unique(row.begin(), row.end()), row.end());
    g.partners.insert(g.partners.end(), row.begin(), row.end());
    g.offsets.push_back(static_cast<Index>(g.partners.size()));
  }
  return g;
}

}  // namespace

SpecialBonds special_bonds(Index n, std::span<const IndexPair> bonds,
                           const std::array<double, 3>& weights) {
  for (std::size_t k = 0; k < 3; ++k) {
    if (!(weights[k] >= 0.0 && weights[k] <= 1.0)) {
      throw std::invalid_argument(
          fmt::format("the 1-{} weight is {} (expected 0 to 1)", k + 2, weights[k]));
    }
  }
  if (n < 0) throw std::invalid_argument("a negative particle count");
  const Graph g = bond_graph(n, bonds);
  SpecialBonds out;
  out.weights = weights;
  out.offsets.reserve(static_cast<std::size_t>(n) + 1);
  // depth[j]: j's distance from the current i (0 for i itself), valid when
  // seen[j] == i + 1; the search's frontier by levels.
  std::vector<std::uint8_t> depth(static_cast<std::size_t>(n), 0);
  std::vector<Index> seen(static_cast<std::size_t>(n), 0);
  std::vector<Index> found, level, next;
  std::vector<std::pair<Index, std::uint8_t>> row;
  for (Index i = 0; i < n; ++i) {
    seen[static_cast<std::size_t>(i)] = i + 1;
    found.clear();
    level.assign(1, i);
    for (std::uint8_t d = 1; d <= 3 && !level.empty(); ++d) {
      next.clear();
      for (const Index a : level) {
        for (const Index b : g.row(a)) {
          if (seen[static_cast<std::size_t>(b)] == i + 1) continue;
          seen[static_cast<std::size_t>(b)] = i + 1;
          depth[static_cast<std::size_t>(b)] = d;
          next.push_back(b);
          found.push_back(b);
        }
      }
      level.swap(next);
    }
    row.clear();
    for (const Index j : found) {
      const std::uint8_t d = depth[static_cast<std::size_t>(j)];
      if (weights[d - 1u] != 1.0) row.emplace_back(j, d);
    }
    std::sort(row.begin(), row.end());
    for (const auto& [j, d] : row) {
      out.partners.push_back(j);
      out.order.push_back(d);
    }
    out.offsets.push_back(static_cast<Index>(out.partners.size()));
  }
  return out;
}

}  // namespace pdyn
