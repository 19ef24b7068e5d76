// pdyn/special_bonds.hpp — pair forces between bonded particles excluded or
// scaled (since 0.10.0): LAMMPS's `special_bonds lj w12 w13 w14`.
//
// A bonded molecule's pair forces do not act between every two of its
// particles. Two beads joined by a bond already feel the bond; a
// Lennard-Jones repulsion between them on top would fight it (the
// Kremer-Grest FENE chain, K. Kremer & G. S. Grest, J. Chem. Phys. 92,
// 5057, 1990, excludes the bonded pair from its pair interaction, LAMMPS's
// `special_bonds fene`), and force fields scale the pair energy of particles
// two and three bonds apart (AMBER's 1-4 pairs at 1/2, CHARMM's 1-2, 1-3
// and 1-4 at 0). So every pair force weighs the pair (i, j) by
//
//   w = w12 when j is bonded to i (1-2), w13 when they are two bonds apart
//   and not one (1-3), w14 three bonds apart and neither (1-4), 1 otherwise,
//
// multiplying both the pair's energy and its force (LAMMPS's factor_lj). A
// pair of weight 0 is not in the force's list at all, as LAMMPS leaves it
// out of its neighbor list. The partners are counted along the bond graph
// as LAMMPS's Special::build counts them: the 1-3 partners of i are the
// bond partners of i's bond partners, the 1-4 partners the bond partners of
// those, i itself never, and a pair reached by several paths takes its
// shortest (in a ring of three, every pair is 1-2).
//
// A plugin author does nothing: PairForce<Law> (pdyn/pair.hpp) implements
// SpecialBondsTarget below, and the host gives it the scene's SpecialBonds
// (the scene's `special_bonds:` key, docs/scenes.md). A pair force written
// by hand may implement the interface too; the host refuses a scene with
// `special_bonds` and a pair force (a PairReference) that does not, rather
// than run it without the exclusions.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "pdyn/export.hpp"
#include "pdyn/types.hpp"

namespace pdyn {

/// The special partners of every particle and their weights (see the top of
/// this file). Built by special_bonds(); immutable once given to a force.
struct SpecialBonds {
  /// w12, w13, w14: the weight of a 1-2, 1-3 and 1-4 pair, each in [0, 1].
  std::array<double, 3> weights{1.0, 1.0, 1.0};
  /// CSR over particles: particle i's special partners are
  /// partners[offsets[i] .. offsets[i + 1]), ascending, each with its
  /// order[] (1: 1-2, 2: 1-3, 3: 1-4). Only partners whose weight is not 1
  /// are listed: the others are ordinary pairs.
  std::vector<Index> offsets{0};
  std::vector<Index> partners;
  std::vector<std::uint8_t> order;

  /// Number of particles N the partners were counted for.
  Index size() const noexcept { return static_cast<Index>(offsets.size()) - 1; }
  /// True when no pair is weighted (no bonds, or every weight 1).
  bool empty() const noexcept { return partners.empty(); }
  /// True when some listed pair has a weight strictly between 0 and 1 (a
  /// force must then multiply, not only leave pairs out).
  bool scales() const noexcept {
    for (std::size_t k = 0; k < order.size(); ++k) {
      if (weights[order[k] - 1u] != 0.0) return true;
    }
    return false;
  }
  /// The special partners of particle i (none for i >= size()).
  std::span<const Index> partners_of(Index i) const noexcept {
    if (i < 0 || i >= size()) return {};
    const auto b = static_cast<std::size_t>(offsets[static_cast<std::size_t>(i)]);
    const auto e = static_cast<std::size_t>(offsets[static_cast<std::size_t>(i) + 1]);
    return std::span<const Index>(partners).subspan(b, e - b);
  }
  /// The weight of the pair (i, j): w12, w13 or w14 if j is a special
  /// partner of i, 1 otherwise. O(log partners).
  double weight(Index i, Index j) const noexcept {
    const auto row = partners_of(i);
    const auto it = std::lower_bound(row.begin(), row.end(), j);
    if (it == row.end() || *it != j) return 1.0;
    const auto k = static_cast<std::size_t>(offsets[static_cast<std::size_t>(i)]) +
                   static_cast<std::size_t>(it - row.begin());
    return weights[order[k] - 1u];
  }
};

/// The special partners of N particles joined by `bonds` (pairs of indices
/// in [0, N), in any order, repeats allowed), weighted by w12, w13, w14.
/// Throws std::invalid_argument for an index out of range, a particle bonded
/// to itself, or a weight outside [0, 1]. O(N + bonds * degree^3).
PDYN_API SpecialBonds special_bonds(Index n, std::span<const IndexPair> bonds,
                                    const std::array<double, 3>& weights);

/// The optional interface of a pair force that honours special bonds:
/// PairForce<Law> implements it, and the host finds it by dynamic_cast on
/// the Force, so forces built against an earlier SDK keep their vtable (and
/// the host refuses to give them special bonds they would ignore).
class PDYN_API SpecialBondsTarget {
 public:
  virtual ~SpecialBondsTarget();
  /// From the next evaluation on, weighs each pair (i, j) by
  /// special->weight(i, j); nullptr (or an empty set) restores plain pairs.
  /// The force keeps the pointer: the set must not change while it is held.
  virtual void set_special_bonds(std::shared_ptr<const SpecialBonds> special) = 0;
  /// The set in use, or nullptr.
  virtual const SpecialBonds* special_bonds() const = 0;
};

/// A neighbor list's rows with the special pairs applied, as a pair force
/// loops over them: a pair of weight 0 left out, every other kept, with
/// which[k] the index into scale() of its weight (0 for weight 1). Rebuilt
/// from the list after each of its builds, O(listed pairs); header code, so
/// that its layout is the plugin's own.
class SpecialRows {
 public:
  /// Rows of `list_offsets`/`list_indices` (CSR, ascending within a row, as
  /// NeighborList gives them) with `special` applied.
  void build(std::span<const Index> list_offsets, std::span<const Index> list_indices,
             const SpecialBonds& special) {
    scale_ = {1.0, special.weights[0], special.weights[1], special.weights[2]};
    const std::size_t n = list_offsets.empty() ? 0 : list_offsets.size() - 1;
    offsets_.assign(1, 0);
    offsets_.reserve(n + 1);
    indices_.clear();
    indices_.reserve(list_indices.size());
    which_.clear();
    which_.reserve(list_indices.size());
    for (std::size_t i = 0; i < n; ++i) {
      const auto own = special.partners_of(static_cast<Index>(i));
      std::size_t s = 0;
      // Where i's partners start in special.order.
      const std::size_t sb = own.empty() ? 0 : static_cast<std::size_t>(special.offsets[i]);
      for (Index k = list_offsets[i]; k < list_offsets[i + 1]; ++k) {
        const Index j = list_indices[static_cast<std::size_t>(k)];
        while (s < own.size() && own[s] < j) ++s;
        std::uint8_t w = 0;
        if (s < own.size() && own[s] == j) {
          w = special.order[sb + s];
          if (scale_[w] == 0.0) continue;  // excluded: not listed at all
        }
        indices_.push_back(j);
        which_.push_back(w);
      }
      offsets_.push_back(static_cast<Index>(indices_.size()));
    }
  }

  const Index* offsets() const noexcept { return offsets_.data(); }
  const Index* indices() const noexcept { return indices_.data(); }
  /// Per listed pair: 0 (weight 1), 1 (w12), 2 (w13) or 3 (w14).
  const std::uint8_t* which() const noexcept { return which_.data(); }
  /// {1, w12, w13, w14}: the weight of which() = 0 .. 3.
  const std::array<double, 4>& scale() const noexcept { return scale_; }

 private:
  std::vector<Index> offsets_{0};
  std::vector<Index> indices_;
  std::vector<std::uint8_t> which_;
  std::array<double, 4> scale_{1.0, 1.0, 1.0, 1.0};
};

}  // namespace pdyn
