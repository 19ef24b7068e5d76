// nbody: mutual Newtonian gravity of every pair of particles, Plummer-softened
// (Plummer 1911; Aarseth, "Gravitational N-body simulations", 2003, sec. 2.4):
// with d = x_j - x_i and q = |d|^2 + eps^2,
//
//   f_i = sum_{j != i} G m_i m_j d / q^(3/2)
//   U   = -sum_{i < j} G m_i m_j / q^(1/2)
//
// eps = 0 is exact Newtonian gravity (singular when two bodies meet);
// eps > 0 makes close encounters smooth, as collisionless galaxy models need.
//
// Two ways to sum (`method`):
//
// - direct: every pair, O(N^2), exact; fine to a few thousand bodies. Each
//   particle's force is its own sum over j in index order, computed by
//   whichever thread owns i (every pair is evaluated twice, once for each
//   body). The two evaluations of a pair are exact negatives of each other
//   (the same products of the same magnitudes), so momentum is conserved to
//   the rounding of the sums.
//
// - barnes_hut: the octree of Barnes & Hut (Nature 324, 446, 1986), O(N log N).
//   The bodies are sorted into a cube that is split into eight until each
//   cell holds one body; every cell keeps its mass and centre of mass (the
//   monopole). A body then walks the tree from the root and takes a cell of
//   side s whose centre of mass is at distance d as one point mass when
//   s/d < theta, otherwise it opens the cell; a cell holding the body itself
//   is always opened (else the body would pull on itself through the cell's
//   centre of mass, which the s/d test alone allows for theta > 1/sqrt(3)).
//   A point mass is softened as a body is, so a one-body cell acts exactly as
//   in direct summation: two bodies give the direct result bit for bit.
//   The forces are not exactly pairwise opposite (i may see j's cell as a
//   point while j opens i's), so momentum drifts at the level of the force
//   error; the measured error table and drifts are in README.md.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <pdyn/parallel.hpp>
#include <pdyn/plugin.hpp>
#include <pdyn/selection.hpp>

namespace {

using pdyn::Index;
using pdyn::Vec3;

// The Barnes-Hut octree, rebuilt from the positions at every evaluation
// (O(N log N); a tree kept across steps would need the same work to stay
// valid as bodies cross cell walls).
//
// Layout: one flat array of cells in depth-first preorder. A cell's children
// follow it, and `next` is the index just past its subtree, so a walk needs no
// stack: open a cell by going to k + 1, skip it by going to `next` (a
// "threaded" tree). A cell's bodies are the contiguous range [first, first +
// count) of `order`, so "does this cell hold body a" is a range check of
// slot[a], exact where a test of a's position against the cube's walls
// would round. Every array only grows: once the tree has been built a few times,
// rebuilding it allocates nothing.
class Octree {
 public:
  struct Cell {
    Vec3 com;            // centre of mass (m)
    double mass;         // total mass (kg)
    double side2;        // side^2 of the cube (m^2), for the s/d < theta test
    Index first, count;  // its bodies: order[first, first + count)
    Index next;          // the cell after its subtree; k + 1 for a leaf
  };

  // Cells are split until they hold one body, or at this depth: bodies closer
  // than side / 2^32 of the root cube (or at the same point) share a leaf,
  // whose bodies are summed one by one when it is opened. Termination does
  // not depend on the positions being distinct or even finite.
  static constexpr int kMaxDepth = 32;

  // Builds the tree over the bodies ids[0..n) (positions x, masses m), which
  // must have finite coordinates. Serial: the same tree on every thread count.
  void build(const pdyn::ParticleView& p, const std::vector<Index>& ids) {
    const Index n = static_cast<Index>(ids.size());
    cells_.clear();
    if (n == 0) return;
    if (static_cast<Index>(order_.size()) != n) {
      order_.resize(static_cast<std::size_t>(n));
      scratch_.resize(static_cast<std::size_t>(n));
      slot_.resize(static_cast<std::size_t>(n));
      octant_.resize(static_cast<std::size_t>(n));
    }
    Vec3 lo = p.x.col(ids[0]), hi = lo;
    for (Index a = 0; a < n; ++a) {
      order_[static_cast<std::size_t>(a)] = a;
      lo = lo.cwiseMin(Vec3(p.x.col(ids[static_cast<std::size_t>(a)])));
      hi = hi.cwiseMax(Vec3(p.x.col(ids[static_cast<std::size_t>(a)])));
    }
    // The root is the smallest cube around the bodies' bounding box.
    build_cell(p, ids, 0, n, 0.5 * (lo + hi), (hi - lo).maxCoeff(), 0);
    for (Index s = 0; s < n; ++s) slot_[static_cast<std::size_t>(order_[s])] = s;
  }

  // Calls term(mass, d, |d|^2) for every point mass body a (at xa) interacts
  // with, d pointing from xa to it: accepted cells as their centre of mass,
  // bodies of opened leaves one by one (never a itself).
  template <class Term>
  void walk(Index a, const Vec3& xa, const pdyn::ParticleView& p, const std::vector<Index>& ids,
            double theta2, Term&& term) const {
    const Index sa = slot_[static_cast<std::size_t>(a)];
    const Index cells = static_cast<Index>(cells_.size());
    Index k = 0;
    while (k < cells) {
      const Cell& c = cells_[static_cast<std::size_t>(k)];
      const bool holds_a = c.first <= sa && sa < c.first + c.count;
      if (!holds_a) {
        const Vec3 d = c.com - xa;
        const double r2 = d.squaredNorm();
        // s/d < theta, squared; a one-body cell is that body exactly.
        if (c.count == 1 || c.side2 < theta2 * r2) {
          term(c.mass, d, r2);
          k = c.next;
          continue;
        }
      }
      if (c.next == k + 1) {  // an opened leaf: its bodies one by one
        for (Index s = c.first; s < c.first + c.count; ++s) {
          const Index b = order_[static_cast<std::size_t>(s)];
          if (b == a) continue;
          const Index j = ids[static_cast<std::size_t>(b)];
          const Vec3 d = p.x.col(j) - xa;
          term(p.mass[j], d, d.squaredNorm());
        }
      }
      ++k;  // into an opened cell's children, or past a leaf
    }
  }

  std::size_t size() const { return cells_.size(); }

 private:
  // Appends the cell holding order[first, first + count), a cube of the given
  // centre and side, then its subtree. Returns its index.
  Index build_cell(const pdyn::ParticleView& p, const std::vector<Index>& ids, Index first,
                   Index count, const Vec3& centre, double side, int depth) {
    const Index k = static_cast<Index>(cells_.size());
    cells_.push_back(Cell{Vec3::Zero(), 0.0, side * side, first, count, 0});
    Vec3 moment = Vec3::Zero();
    double mass = 0.0;
    if (count == 1) {
      // The body itself, not m x / m: a one-body cell must act exactly as the
      // body does in direct summation.
      const Index j = ids[static_cast<std::size_t>(order_[static_cast<std::size_t>(first)])];
      cells_[static_cast<std::size_t>(k)].com = p.x.col(j);
      cells_[static_cast<std::size_t>(k)].mass = p.mass[j];
      cells_[static_cast<std::size_t>(k)].next = k + 1;
      return k;
    }
    if (depth == kMaxDepth) {
      for (Index s = first; s < first + count; ++s) {
        const Index j = ids[static_cast<std::size_t>(order_[static_cast<std::size_t>(s)])];
        mass += p.mass[j];
        moment += p.mass[j] * Vec3(p.x.col(j));
      }
    } else {
      // Counting sort of the range into the eight octants (bit 0: x above
      // the centre, bit 1: y, bit 2: z), stable, so the tree depends on the
      // positions and the bodies' order only.
      std::array<Index, 8> begin{}, fill{};
      for (Index s = first; s < first + count; ++s) {
        const Index j = ids[static_cast<std::size_t>(order_[static_cast<std::size_t>(s)])];
        const int o = (p.x(0, j) >= centre.x() ? 1 : 0) | (p.x(1, j) >= centre.y() ? 2 : 0) |
                      (p.x(2, j) >= centre.z() ? 4 : 0);
        octant_[static_cast<std::size_t>(s)] = static_cast<std::uint8_t>(o);
        ++begin[static_cast<std::size_t>(o)];
      }
      Index at = first;
      for (std::size_t o = 0; o < 8; ++o) {
        const Index c = begin[o];
        begin[o] = fill[o] = at;
        at += c;
      }
      for (Index s = first; s < first + count; ++s) {
        const std::size_t o = octant_[static_cast<std::size_t>(s)];
        scratch_[static_cast<std::size_t>(fill[o]++)] = order_[static_cast<std::size_t>(s)];
      }
      std::copy(scratch_.begin() + first, scratch_.begin() + first + count, order_.begin() + first);
      const double quarter = 0.25 * side;
      for (std::size_t o = 0; o < 8; ++o) {
        const Index n = fill[o] - begin[o];
        if (n == 0) continue;
        const Vec3 c(centre.x() + ((o & 1) ? quarter : -quarter),
                     centre.y() + ((o & 2) ? quarter : -quarter),
                     centre.z() + ((o & 4) ? quarter : -quarter));
        const Index child = build_cell(p, ids, begin[o], n, c, 0.5 * side, depth + 1);
        const Cell& cc = cells_[static_cast<std::size_t>(child)];
        mass += cc.mass;
        moment += cc.mass * cc.com;
      }
    }
    Cell& cell = cells_[static_cast<std::size_t>(k)];
    cell.mass = mass;
    // Massless cells (test particles only) pull on nothing; any finite point will do.
    cell.com = mass > 0.0 ? Vec3(moment / mass) : centre;
    cell.next = static_cast<Index>(cells_.size());
    return k;
  }

  std::vector<Cell> cells_;
  std::vector<Index> order_;    // bodies (positions in ids) in tree order
  std::vector<Index> scratch_;  // the counting sort's output
  std::vector<Index> slot_;     // slot_[a]: where body a is in order_
  std::vector<std::uint8_t> octant_;
};

enum class Method { Direct, BarnesHut };

class NBody final : public pdyn::Force {
 public:
  NBody(double g, double eps, Method method, double theta, pdyn::Selection selection)
      : g_(g),
        eps2_(eps * eps),
        method_(method),
        theta2_(theta * theta),
        selection_(std::move(selection)) {}

  // Newton's law of gravitation reads positions and masses only.
  pdyn::StateDependence dependence() const override { return {false, false}; }

  void add_forces(const pdyn::ParticleView& p, Eigen::Ref<pdyn::Matrix3X> f) override {
    const std::vector<Index>& ids = members(p);
    const Index n = static_cast<Index>(ids.size());
    if (method_ == Method::BarnesHut) {
      if (!build_tree(p, ids)) {
        // A non-finite position: no tree, and no meaningful force. The
        // runner stops on the non-finite state; NaN says why.
        for (const Index i : ids) f.col(i).array() += std::numeric_limits<double>::quiet_NaN();
        return;
      }
      pdyn::parallel_ranges(n, [&](Index begin, Index end) {
        for (Index a = begin; a < end; ++a) {
          const Index i = ids[static_cast<std::size_t>(a)];
          Vec3 sum = Vec3::Zero();
          tree_.walk(a, p.x.col(i), p, ids, theta2_, [&](double m, const Vec3& d, double r2) {
            const double q = r2 + eps2_;
            sum += (m / (q * std::sqrt(q))) * d;
          });
          f.col(i) += (g_ * p.mass[i]) * sum;
        }
      });
      return;
    }
    pdyn::parallel_ranges(n, [&](Index begin, Index end) {
      for (Index a = begin; a < end; ++a) {
        const Index i = ids[static_cast<std::size_t>(a)];
        const Vec3 xi = p.x.col(i);
        Vec3 sum = Vec3::Zero();
        for (Index b = 0; b < n; ++b) {
          if (b == a) continue;
          const Index j = ids[static_cast<std::size_t>(b)];
          const Vec3 d = p.x.col(j) - xi;
          const double q = d.squaredNorm() + eps2_;
          sum += (p.mass[j] / (q * std::sqrt(q))) * d;
        }
        f.col(i) += (g_ * p.mass[i]) * sum;
      }
    });
  }

  // barnes_hut: the potential of the same tree the forces come from,
  // U = 1/2 sum_i m_i phi_i with phi_i = -G sum over what body i interacts
  // with of M / q^(1/2) (each pair counted once on average over its two
  // ends). O(N log N), like the forces, so that the energy checks of a large
  // run (the runner's, every 64 steps, and `output.energy`) stay cheap;
  // its error is below the forces' (README.md's table).
  std::optional<double> potential_energy(const pdyn::ParticleView& p) const override {
    const std::vector<Index>& ids = members(p);
    if (method_ == Method::BarnesHut) {
      if (!build_tree(p, ids)) return std::numeric_limits<double>::quiet_NaN();
      const Index n = static_cast<Index>(ids.size());
      phi_.resize(ids.size());
      pdyn::parallel_ranges(n, [&](Index begin, Index end) {
        for (Index a = begin; a < end; ++a) {
          const Index i = ids[static_cast<std::size_t>(a)];
          double phi = 0.0;
          tree_.walk(a, p.x.col(i), p, ids, theta2_,
                     [&](double m, const Vec3&, double r2) { phi -= m / std::sqrt(r2 + eps2_); });
          phi_[static_cast<std::size_t>(a)] = p.mass[i] * phi;
        }
      });
      double u = 0.0;  // summed in body order: the same bits on any thread count
      for (const double e : phi_) u += e;
      return 0.5 * g_ * u;
    }
    double u = 0.0;
    for (std::size_t a = 0; a < ids.size(); ++a) {
      for (std::size_t b = a + 1; b < ids.size(); ++b) {
        const double q = (p.x.col(ids[b]) - p.x.col(ids[a])).squaredNorm() + eps2_;
        u -= g_ * p.mass[ids[a]] * p.mass[ids[b]] / std::sqrt(q);
      }
    }
    return u;
  }

 private:
  // The bodies: the selection, or every particle (kept up to date when a
  // host adds particles).
  const std::vector<Index>& members(const pdyn::ParticleView& p) const {
    if (!selection_.all()) return selection_.ids();
    if (static_cast<Index>(all_.size()) != p.size()) {
      all_.resize(static_cast<std::size_t>(p.size()));
      for (Index i = 0; i < p.size(); ++i) all_[static_cast<std::size_t>(i)] = i;
    }
    return all_;
  }

  // Rebuilds the tree for the current positions; false if one is not finite.
  bool build_tree(const pdyn::ParticleView& p, const std::vector<Index>& ids) const {
    for (const Index i : ids) {
      if (!p.x.col(i).allFinite()) return false;
    }
    tree_.build(p, ids);
    return true;
  }

  double g_, eps2_;
  Method method_;
  double theta2_;
  pdyn::Selection selection_;
  mutable std::vector<Index> all_;
  mutable Octree tree_;              // scratch, rebuilt at every call
  mutable std::vector<double> phi_;  // m_i phi_i / G per body
};

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Force;
  d.name = "nbody";
  d.version = "1.1.0";
  d.description =
      "mutual gravity f_i = sum_j G m_i m_j d / (|d|^2 + eps^2)^(3/2), Plummer softening; direct "
      "summation or a Barnes-Hut tree";
  d.params = {
      pdyn::param::real("G", 6.6743e-11, "m^3/(kg s^2)", "gravitational constant").greater_than(0),
      pdyn::param::real("softening", 0.0, "m", "Plummer softening length eps").at_least(0),
      pdyn::param::string("method", "direct",
                          "direct (every pair, exact, O(N^2)) or barnes_hut (octree, O(N log N))"),
      pdyn::param::optional("theta", pdyn::ParamType::Real, "",
                            "barnes_hut opening angle (0.5 if not given): a cell of side s at "
                            "distance d acts as its centre of mass when s/d < theta")
          .greater_than(0)
          .at_most(1),
  };
  for (auto& s : pdyn::selection_params()) d.params.push_back(std::move(s));
  // Declared for the default, direct summation; barnes_hut keeps momentum
  // only to the tree's force error (README.md).
  d.force_traits.internal = true;  // pairwise equal and opposite, central
  d.force_traits.singular = true;  // with softening 0, infinite where two bodies meet
  d.create_force = [](const pdyn::Params& p, const pdyn::SceneContext& ctx) {
    const std::string& name = p.string("method");
    Method method = Method::Direct;
    if (name == "barnes_hut") {
      method = Method::BarnesHut;
    } else if (name != "direct") {
      throw pdyn::ParamError("method",
                             fmt::format("'{}' is not a summation method (expected one of: direct, "
                                         "barnes_hut)",
                                         name));
    }
    // A theta that would be ignored is refused, not silently dropped.
    if (method == Method::Direct && p.has("theta")) {
      throw pdyn::ParamError("theta",
                             "only the barnes_hut method has an opening angle (expected method: "
                             "barnes_hut, or no theta)");
    }
    const double theta = p.has("theta") ? p.real("theta") : 0.5;
    return std::make_unique<NBody>(p.real("G"), p.real("softening"), method, theta,
                                   pdyn::Selection::from_params(p, ctx));
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
