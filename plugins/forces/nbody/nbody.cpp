// nbody: mutual Newtonian gravity of every pair of particles, by direct
// summation, Plummer-softened (Plummer 1911; Aarseth, "Gravitational N-body
// simulations", 2003, sec. 2.4): with d = x_j - x_i and q = |d|^2 + eps^2,
//
//   f_i = sum_{j != i} G m_i m_j d / q^(3/2)
//   U   = -sum_{i < j} G m_i m_j / q^(1/2)
//
// eps = 0 is exact Newtonian gravity (singular when two bodies meet);
// eps > 0 makes close encounters smooth, as collisionless galaxy models need.
// O(N^2): fine to a few thousand bodies.
//
// Threads, bit for bit: each particle's force is its own sum over j in index
// order, computed by whichever thread owns i (every pair is evaluated twice,
// once for each body). The two evaluations of a pair are exact negatives of
// each other (the same products of the same magnitudes), so momentum is
// conserved to the rounding of the sums.
#include <cmath>
#include <pdyn/parallel.hpp>
#include <pdyn/plugin.hpp>
#include <pdyn/selection.hpp>

namespace {

using pdyn::Index;
using pdyn::Vec3;

class NBody final : public pdyn::Force {
 public:
  NBody(double g, double eps, pdyn::Selection selection)
      : g_(g), eps2_(eps * eps), selection_(std::move(selection)) {}

  void add_forces(const pdyn::ParticleView& p, Eigen::Ref<pdyn::Matrix3X> f) override {
    const std::vector<Index>& ids = members(p);
    const Index n = static_cast<Index>(ids.size());
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

  std::optional<double> potential_energy(const pdyn::ParticleView& p) const override {
    const std::vector<Index>& ids = members(p);
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

  double g_, eps2_;
  pdyn::Selection selection_;
  mutable std::vector<Index> all_;
};

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Force;
  d.name = "nbody";
  d.version = "1.0.0";
  d.description =
      "mutual gravity f_i = sum_j G m_i m_j d / (|d|^2 + eps^2)^(3/2), direct summation, Plummer "
      "softening";
  d.params = {
      pdyn::param::real("G", 6.6743e-11, "m^3/(kg s^2)", "gravitational constant").greater_than(0),
      pdyn::param::real("softening", 0.0, "m", "Plummer softening length eps").at_least(0),
  };
  for (auto& s : pdyn::selection_params()) d.params.push_back(std::move(s));
  d.force_traits.internal = true;  // pairwise equal and opposite, central
  d.force_traits.singular = true;  // with softening 0, infinite where two bodies meet
  d.create_force = [](const pdyn::Params& p, const pdyn::SceneContext& ctx) {
    return std::make_unique<NBody>(p.real("G"), p.real("softening"),
                                   pdyn::Selection::from_params(p, ctx));
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
