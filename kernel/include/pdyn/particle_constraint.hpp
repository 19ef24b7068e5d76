// pdyn/particle_constraint.hpp — constraints that hold particles one at a
// time: the author writes one particle's rows, the base class the rest.
//
// A pin, a bead on a plane, a sphere, a wire or a bowl constrains each
// listed particle by itself: every row involves one particle, and each
// particle has the same few rows about its own piece of geometry (its
// point, its plane's offset, its radius). What differs between them is one
// small function of one particle's position, velocity and the time; the
// pattern, the loop over the particles and where each row's numbers go are
// the same for all. As BondedForce<Law> does for bonded terms
// (pdyn/bonded.hpp), a plugin supplies a *law* and instantiates
// ParticleConstraint<Law>:
//
//   struct Law {
//     static constexpr int rows = 2;   // rows per particle: 1 (a plane), 2 (a wire), 3 (a pin)
//     using Site = double;             // what each particle keeps: its radius, point, offset
//     // Row c of one particle, c = 0 .. rows-1, at its position, velocity and
//     // the time: C, J = dC/dx of that particle, c_t and b, as pdyn/constraint.hpp
//     // defines them. rate and bias come zeroed, value and jacobian NaN:
//     // a row left unwritten fails `pdyn check`, never passes as 0.
//     void operator()(const pdyn::ParticlePoint& p, const Site& site,
//                     pdyn::ParticleRows<rows>& out) const;
//   };
//
//   using Bowl = pdyn::ParticleConstraint<BowlLaw>;
//   return std::make_unique<Bowl>(ids, std::move(sites), BowlLaw{radius});
//
// The rows of the particle ids[k] are the constraint's rows rows k .. rows k
// + rows - 1, each with one Jacobian entry. The base class writes that entry
// where pdyn/constraint.hpp's layout puts it, out.jacobian.col(row_begin[r]):
// a row's entries start at row_begin[r], which here is r because every row
// has one. A row over two or more particles (a rod, a hinge) does not fit
// this family: derive from pdyn::Constraint and write its particle j's entry
// at row_begin[r] + j (plugins/constraints/distance).
//
// The factory checks the ids once (at least one, each once:
// require_distinct_ids in pdyn/params.hpp) and gives each particle its site,
// from the parameters or from where the particle starts, so that C = 0 at
// the start (docs/constraints.md).
#pragma once

#include <array>
#include <limits>
#include <utility>
#include <vector>

#include "pdyn/constraint.hpp"
#include "pdyn/types.hpp"

namespace pdyn {

/// One particle as a per-particle law sees it.
struct ParticlePoint {
  Vec3 x;          ///< position, m
  Vec3 v;          ///< velocity, m/s
  double t = 0.0;  ///< time, s
};

/// One particle's rows as a law writes them (row c: value[c], jacobian[c], ...).
template <int Rows>
struct ParticleRows {
  static_assert(Rows >= 1, "a particle's constraint has at least one row");
  static constexpr double kUnwritten = std::numeric_limits<double>::quiet_NaN();
  std::array<double, Rows> value;   ///< C, the row's unit; NaN until written
  std::array<double, Rows> rate;    ///< c_t, unit/s; 0 unless written
  std::array<double, Rows> bias;    ///< b, unit/s^2; 0 unless written
  std::array<Vec3, Rows> jacobian;  ///< dC/dx of the particle, unit/m; NaN until written

  ParticleRows() {
    value.fill(kUnwritten);
    rate.fill(0.0);
    bias.fill(0.0);
    jacobian.fill(Vec3::Constant(kUnwritten));
  }
};

/// A constraint whose rows each hold one particle: Law::rows rows for each
/// of `ids`, written by the law one particle at a time.
template <class Law>
class ParticleConstraint : public Constraint {
 public:
  static constexpr int kRows = Law::rows;
  using Site = typename Law::Site;

  /// `ids`: the particles, each once; `sites`: one per id, in the same order.
  ParticleConstraint(std::vector<Index> ids, std::vector<Site> sites, Law law = Law{})
      : ids_(std::move(ids)), sites_(std::move(sites)), law_(std::move(law)) {
    for (const Index i : ids_) {
      for (int c = 0; c < kRows; ++c) pattern_.add_row({i});
    }
  }

  ConstraintPattern pattern() const override { return pattern_; }

  void evaluate(const ParticleView& p, ConstraintValues& out) const override {
    for (std::size_t k = 0; k < ids_.size(); ++k) {
      const Index i = ids_[k];
      ParticleRows<kRows> rows;
      law_(ParticlePoint{p.x.col(i), p.v.col(i), p.t}, sites_[k], rows);
      for (int c = 0; c < kRows; ++c) {
        const Index r = kRows * static_cast<Index>(k) + c;
        out.value[r] = rows.value[c];
        out.rate[r] = rows.rate[c];
        out.bias[r] = rows.bias[c];
        // The row's one entry: its first, row_begin[r] (= r in this family).
        out.jacobian.col(pattern_.row_begin[r]) = rows.jacobian[c];
      }
    }
  }

  /// The constrained particles, in the order given.
  const std::vector<Index>& ids() const noexcept { return ids_; }
  /// Each particle's site, in the order of ids().
  const std::vector<Site>& sites() const noexcept { return sites_; }
  const Law& law() const noexcept { return law_; }

 private:
  std::vector<Index> ids_;
  std::vector<Site> sites_;
  Law law_;
  ConstraintPattern pattern_;
};

}  // namespace pdyn
