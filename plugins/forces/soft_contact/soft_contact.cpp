// soft_contact: particle-particle contact of the discrete element method
// (Cundall & Strack 1979), the linear spring-dashpot model: two particles of
// radii R_i, R_j whose centres are closer than R_i + R_j overlap by
// delta = R_i + R_j - r and push each other apart along n = (x_i - x_j) / r:
//
//   F_n = (k delta - gamma v_n) n,      v_n = (v_i - v_j) . n
//
// The dashpot gamma gives a head-on collision the restitution coefficient e
// exactly (the damped oscillator of the overlap, of reduced mass
// m* = m_i m_j / (m_i + m_j), half a period long):
//
//   gamma = -2 ln(e) sqrt(m* k) / sqrt(pi^2 + ln^2 e)
//
// The normal force is not clipped at 0 at the end of a contact, so that e
// is exact (as in LAMMPS's gran/hooke); the small pull it leaves lasts less
// than one contact time.
//
// Coulomb friction opposes the tangential slip v_t = v_rel - v_n n, viscous
// while slow and capped at mu |F_n| (history-free, as in the simplest DEM
// codes: a heap still comes to rest, without the springs of static
// friction):  F_t = -min(gamma |v_t|, mu |F_n|) v_t / |v_t|.
//
// The pair loop, neighbor list (cutoff: the largest diameter), threads and
// periodic images are the kernel's (pdyn/pair.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <pdyn/pair.hpp>
#include <pdyn/plugin.hpp>
#include <pdyn/selection.hpp>

namespace {

using pdyn::Vec3;

struct Contact {
  double k;                // normal stiffness, N/m
  double damping;          // -2 ln(e) / sqrt(pi^2 + ln^2 e): gamma = damping sqrt(m* k)
  double mu;               // Coulomb friction coefficient
  double fallback_radius;  // m, for particles the scene gives none (< 0: none)

  double radius(const pdyn::ParticleView& p, pdyn::Index i) const {
    return p.radius.empty() ? fallback_radius : p.radius[static_cast<std::size_t>(i)];
  }

  // m* of the pair's relative motion; a nailed particle does not move, so
  // against it m* is the free particle's mass (a ball on a fixed ball
  // bounces with e too).
  static double reduced_mass(const pdyn::ParticleView& p, pdyn::Index i, pdyn::Index j) {
    const double mi = p.mass[i], mj = p.mass[j];
    const bool fi = p.fixed[static_cast<std::size_t>(i)] != 0,
               fj = p.fixed[static_cast<std::size_t>(j)] != 0;
    if (fi != fj) return fi ? mj : mi;
    return mi * mj / (mi + mj);
  }

  pdyn::PairVector operator()(const pdyn::ParticleView& p, const pdyn::PairPoint& q) const {
    const double reach = radius(p, q.i) + radius(p, q.j);
    if (!(q.r2 < reach * reach) || q.r2 == 0.0) return {};
    const double r = std::sqrt(q.r2);
    const double overlap = reach - r;
    const Vec3 n = q.d / r;
    const Vec3 v = p.v.col(q.i) - p.v.col(q.j);
    const double vn = v.dot(n);
    const double gamma = damping * std::sqrt(reduced_mass(p, q.i, q.j) * k);
    const double fn = k * overlap - gamma * vn;
    Vec3 f = fn * n;
    if (mu > 0.0) {
      const Vec3 vt = v - vn * n;
      const double slip = vt.norm();
      if (slip > 0.0) f -= std::min(gamma * slip, mu * std::abs(fn)) / slip * vt;
    }
    return {0.5 * k * overlap * overlap, f};
  }
};

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Force;
  d.name = "soft_contact";
  d.version = "1.0.0";
  d.description =
      "DEM contact between particles with radii: linear spring-dashpot normal force with a "
      "restitution coefficient, Coulomb friction";
  d.params = {
      pdyn::param::real("stiffness", 1e4, "N/m", "normal spring k").greater_than(0),
      pdyn::param::real("restitution", 0.5, "",
                        "coefficient of restitution e of a head-on "
                        "collision")
          .greater_than(0)
          .at_most(1),
      pdyn::param::real("friction", 0.3, "", "Coulomb friction coefficient mu").at_least(0),
      pdyn::param::optional("radius", pdyn::ParamType::Real, "m",
                            "radius of every particle, when the scene gives none"),
      pdyn::param::optional("skin", pdyn::ParamType::Real, "m",
                            "neighbor-list skin (default: a fifth of the largest diameter)"),
  };
  for (auto& s : pdyn::selection_params()) d.params.push_back(std::move(s));
  d.create_force = [](const pdyn::Params& p, const pdyn::SceneContext& ctx) {
    const auto& radii = ctx.particles.radius;
    double fallback = -1.0;
    if (p.has("radius")) {
      fallback = p.real("radius");
      if (!(fallback > 0.0)) {
        throw pdyn::ParamError("radius",
                               fmt::format("{} m is not a radius (expected > 0 m)", fallback));
      }
    } else if (radii.empty()) {
      throw pdyn::ParamError("radius",
                             "is needed: no particle has a radius (expected `radius:` on the "
                             "particles, `particle_radius:` on a builder, or this force's "
                             "`radius:`)");
    }
    const double largest =
        radii.empty() ? fallback : std::max(0.0, *std::max_element(radii.begin(), radii.end()));
    if (!(largest > 0.0)) {
      throw pdyn::ParamError("radius", "every particle has radius 0 (expected some radius > 0 m)");
    }
    const double cutoff = 2.0 * largest;
    const double skin = p.has("skin") ? p.real("skin") : 0.2 * cutoff;
    if (!(skin >= 0.0)) {
      throw pdyn::ParamError("skin", fmt::format("{} m is not a skin (expected >= 0 m)", skin));
    }
    pdyn::check_cutoff_fits(ctx.particles.domain, cutoff, skin);
    const double e = p.real("restitution"), ln = std::log(e);
    const Contact law{p.real("stiffness"),
                      -2.0 * ln / std::sqrt(std::numbers::pi * std::numbers::pi + ln * ln),
                      p.real("friction"), fallback};
    return std::make_unique<pdyn::PairForce<Contact>>(
        law, cutoff, skin, pdyn::Selection::from_params(p, ctx).mask(ctx.particles.size()));
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
