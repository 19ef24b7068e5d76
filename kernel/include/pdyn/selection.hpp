// pdyn/selection.hpp — which particles a force acts on: all of them, a named
// group, or a list of particle ids.
//
// A force that acts on particles one at a time (gravity, drag, a field)
// appends selection_params() to its descriptor's parameters and resolves
// them once, in its factory, with Selection::from_params:
//
//   forces:
//     - { type: gravity }                     # every particle
//     - { type: drag, group: cloth }          # the grid built with name: cloth
//     - { type: field, ids: [0, 3, 7], ... }  # three particles
//
// Groups are the names that builders give (`grid: { name: cloth }`); the
// scene loader passes them in SceneContext::groups.
#pragma once

#include <cstdint>
#include <vector>

#include "pdyn/export.hpp"
#include "pdyn/params.hpp"
#include "pdyn/plugin.hpp"

namespace pdyn {

/// The two optional keys of a selectable force:
///   `group` (string): a group defined by a builder's `name:`;
///   `ids` (index list): particle indices, each at most once.
/// Neither given: every particle. Both: an error.
PDYN_API std::vector<ParamSpec> selection_params();

/// The particles a force acts on, resolved once at construction.
class PDYN_API Selection {
 public:
  /// Every particle.
  Selection() = default;

  /// Resolves `group` / `ids` (declared by selection_params()) against
  /// `ctx.groups`. Throws ParamError, which the scene loader reports at the
  /// offending key, when both are given, when the group is not defined
  /// (listing the groups that are, with "did you mean" for a likely typo),
  /// or when `ids` is empty or names a particle twice.
  static Selection from_params(const Params& params, const SceneContext& ctx);

  /// True: the force acts on every particle, and ids() is empty.
  bool all() const noexcept { return all_; }
  /// The selected particle indices, in the order given (a group: the order
  /// its builder made them); only meaningful when !all().
  const std::vector<Index>& ids() const noexcept { return ids_; }
  /// The selection as N membership flags (1: selected), the form
  /// NeighborList and PairForce take; empty when all().
  std::vector<std::uint8_t> mask(Index n) const;

 private:
  bool all_ = true;
  std::vector<Index> ids_;
};

}  // namespace pdyn
