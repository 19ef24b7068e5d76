// soft_contact: particle-particle contact of the discrete element method
// (Cundall & Strack 1979). Two particles of radii R_i, R_j whose centres are
// closer than R_i + R_j overlap by delta = R_i + R_j - r and push each other
// apart along n = (x_i - x_j) / r, with the normal relative velocity
// v_n = (v_i - v_j) . n = -d(delta)/dt and the reduced mass
// m* = m_i m_j / (m_i + m_j). Two normal laws (`model`):
//
// linear, the spring-dashpot:   F_n = k delta - gamma v_n,
//   gamma = -2 ln(e) sqrt(m* k) / sqrt(pi^2 + ln^2 e)
// gives a head-on collision the restitution coefficient e exactly (the
// damped oscillator of the overlap, half a period long). F_n is not clipped
// at 0 at the end of a contact, so that e is exact (as in LAMMPS's
// gran/hooke); the small pull it leaves lasts less than one contact time.
//
// hertz, elastic spheres (Hertz 1882) with the damping of Tsuji, Tanaka &
// Ishida (Powder Technology 71:239, 1992):
//   F_n = max(0, k delta^(3/2) - alpha sqrt(m* k) delta^(1/4) v_n),
// k in N/m^(3/2). In units of the impact speed v0 and of the time
// (m*/k)^(2/5) v0^(-1/5), a head-on collision is the ODE
//   x'' = -max(0, x^(3/2) + alpha x^(1/4) x'),   x(0) = 0, x'(0) = 1,
// with neither m*, k nor v0 left in it: its restitution -x'(end) depends on
// alpha alone, and the contact lasts tau(alpha) (m*/k)^(2/5) v0^(-1/5).
// The factory solves e(alpha) = e for alpha (bisection on RK4 integrations
// of the ODE, hertz_alpha below) instead of using a curve fit. F_n is
// clamped at 0 (no pull, LAMMPS granular's `limit_damping`, LIGGGHTS's
// `limitForce`): without the clamp the tensile end of the contact makes
// e(alpha) fall to 0 near alpha = 2.2 (the pair sticks), with it every e in
// (0, 1] has an alpha, and the ODE solved is the clamped one, so e holds for
// the law as implemented.
//
// Coulomb friction opposes the tangential slip v_t = v_rel - v_n n, viscous
// while slow and capped at mu |F_n| (history-free, as in the simplest DEM
// codes: a heap still comes to rest, without the springs of static
// friction):  F_t = -min(gamma |v_t|, mu |F_n|) v_t / |v_t|, with the normal
// damping coefficient gamma of the law (hertz: alpha sqrt(m* k) delta^(1/4)).
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
#include <pdyn/text.hpp>
#include <string>
#include <vector>

namespace {

using pdyn::Vec3;

enum class Model { Linear, Hertz };

// The restitution coefficient of the dimensionless Hertz collision
//   x'' = -max(0, x^(3/2) + alpha x^(1/4) x'),  x(0) = 0, x'(0) = 1
// (see the top of this file): -x' when x is back to 0. Classic RK4 with
// step 1e-3: the contact lasts 3.2 (alpha = 0) to 17 (alpha = 10, e = 0.011)
// units, and halving the step changes e by less than 1e-5. After the force
// has fallen to 0 (the clamp) x' no longer changes, so the step that
// crosses x = 0 reads e exactly.
double hertz_restitution(double alpha) {
  const auto accel = [alpha](double x, double v) {
    const double s = std::max(x, 0.0), root = std::sqrt(s);
    return -std::max(0.0, s * root + alpha * std::sqrt(root) * v);
  };
  constexpr double h = 1e-3;
  double x = 0.0, v = 1.0;
  while (true) {
    const double a1 = accel(x, v);
    const double x2 = x + 0.5 * h * v, v2 = v + 0.5 * h * a1, a2 = accel(x2, v2);
    const double x3 = x + 0.5 * h * v2, v3 = v + 0.5 * h * a2, a3 = accel(x3, v3);
    const double x4 = x + h * v3, v4 = v + h * a3, a4 = accel(x4, v4);
    x += h / 6 * (v + 2 * v2 + 2 * v3 + v4);
    v += h / 6 * (a1 + 2 * a2 + 2 * a3 + a4);
    if (x <= 0.0) return -v;  // the force is back to 0 only once v < 0
  }
}

// The alpha of the hertz model whose head-on collisions bounce with
// restitution e in (0, 1]: e(alpha) falls from 1 at alpha = 0, monotonically
// (about 1.2 / alpha^2 for large alpha), so bracket by doubling and bisect to
// 1e-9 relative: some 35 integrations, once per force, a few milliseconds
// (e = 0.01: 40 ms, the contact lasting longer). Check of the integrator:
// without the clamp it gives Antypov & Elliott's analytic relation
// alpha = sqrt(5) (-ln e) / sqrt(pi^2 + ln^2 e) (EPL 94:50004, 2011) to
// 3e-6; with the clamp that alpha would give e = 0.55 for 0.5, 0.25 for 0.1.
constexpr double kHertzSmallestRestitution = 1e-3;  // alpha = 35, 0.2 s to solve

double hertz_alpha(double e) {
  if (e >= 1.0) return 0.0;
  double lo = 0.0, hi = 1.0;
  while (hertz_restitution(hi) > e) {
    lo = hi;
    hi *= 2.0;
  }
  while (hi - lo > 1e-9 * hi) {
    const double mid = 0.5 * (lo + hi);
    (hertz_restitution(mid) > e ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

struct Contact {
  Model model;
  double k;                // normal stiffness: N/m (linear), N/m^(3/2) (hertz)
  double damping;          // linear: -2 ln(e) / sqrt(pi^2 + ln^2 e), gamma = damping sqrt(m* k);
                           // hertz: alpha, gamma = alpha sqrt(m* k) delta^(1/4)
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
    double gamma, fn, energy;
    if (model == Model::Linear) {
      gamma = damping * std::sqrt(reduced_mass(p, q.i, q.j) * k);
      fn = k * overlap - gamma * vn;
      energy = 0.5 * k * overlap * overlap;
    } else {
      const double root = std::sqrt(overlap);  // delta^(1/2)
      gamma = damping * std::sqrt(reduced_mass(p, q.i, q.j) * k) * std::sqrt(root);
      fn = std::max(0.0, k * overlap * root - gamma * vn);
      energy = 0.4 * k * overlap * overlap * root;  // 2/5 k delta^(5/2)
    }
    Vec3 f = fn * n;
    if (mu > 0.0) {
      const Vec3 vt = v - vn * n;
      const double slip = vt.norm();
      if (slip > 0.0) f -= std::min(gamma * slip, mu * std::abs(fn)) / slip * vt;
    }
    return {energy, f};
  }
};

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Force;
  d.name = "soft_contact";
  d.version = "1.1.0";
  d.description =
      "DEM contact between particles with radii: linear spring-dashpot or Hertz normal force "
      "with a restitution coefficient, Coulomb friction";
  d.params = {
      pdyn::param::string("model", "linear",
                          "normal force: linear (k delta) or hertz (k delta^(3/2)), each with "
                          "the damping of an exact restitution"),
      pdyn::param::real("stiffness", 1e4, "N/m (hertz: N/m^1.5)", "normal stiffness k")
          .greater_than(0),
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
    const std::string& name = p.string("model");
    if (name != "linear" && name != "hertz") {
      const std::vector<std::string> models = {"linear", "hertz"};
      const std::string guess = pdyn::closest_match(name, models);
      throw pdyn::ParamError(
          "model", fmt::format("unknown model '{}' ({}expected one of: {})", name,
                               guess.empty() ? "" : fmt::format("did you mean '{}'? ", guess),
                               pdyn::join(models)));
    }
    const Model model = name == "hertz" ? Model::Hertz : Model::Linear;
    const double e = p.real("restitution"), ln = std::log(e);
    if (model == Model::Hertz && e < kHertzSmallestRestitution) {
      throw pdyn::ParamError("restitution",
                             fmt::format("{} is too small for model: hertz (expected >= {}: the "
                                         "collision that gives alpha lasts as 1 / sqrt(e))",
                                         e, kHertzSmallestRestitution));
    }
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
    const double damping =
        model == Model::Hertz
            ? hertz_alpha(e)
            : -2.0 * ln / std::sqrt(std::numbers::pi * std::numbers::pi + ln * ln);
    const Contact law{model, p.real("stiffness"), damping, p.real("friction"), fallback};
    return std::make_unique<pdyn::PairForce<Contact>>(
        law, cutoff, skin, pdyn::Selection::from_params(p, ctx).mask(ctx.particles.size()));
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
