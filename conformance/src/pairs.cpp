// The pair checks: what a pair force (pdyn/pair.hpp) must do beyond what
// every force must. A pair force is fast because of its neighbor list and
// the loop around the law; these checks compare that fast path with the
// physics it stands for, through the optional interface PairReference
// (the cutoff, a brute-force sum over all pairs, a declared continuous
// energy), found with dynamic_cast as the collider checks find ShapeSource:
//
//   pair.newton_third_law    two particles, both labellings: f_A = -f_B, and
//                            the force on A the same whichever is particle 0
//   pair.gradient            the radial force is -dU/dr (central differences)
//                            at five distances below the cutoff
//   pair.matches_brute_force add_forces and potential_energy equal the
//                            all-pairs sum on random configurations, open and
//                            periodic, moved over several calls (list rebuilds)
//   pair.continuous_at_cutoff U(rc^-) = 0 when the energy is declared
//                            continuous (or with a boolean `shift` on)
//   pair.special_bonds       with special bonds (pdyn/special_bonds.hpp)
//                            on a bond graph of near neighbours, the list's
//                            forces and energy equal the all-pairs sum with
//                            the same weights, excluded and scaled
//
// Distances scale with the cutoff rc, so that one set of checks fits a
// Lennard-Jones fluid (rc = 2.5 sigma) and a contact law (rc = a diameter).
// Two particles are never closer than 0.35 rc: a singular law stays finite.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>

#include "checks.hpp"
#include "pdyn/pair.hpp"
#include "pdyn/special_bonds.hpp"
#include "sample.hpp"

namespace pdyn::conformance::detail {

namespace {

// The distances, as fractions of rc, at which two particles are placed.
constexpr double kFractions[] = {0.4, 0.55, 0.7, 0.85, 0.97};
// No two particles of a random configuration closer than this, times rc.
constexpr double kMinDistance = 0.35;
// The configurations' number density: about 12.6 neighbours within rc.
constexpr double kDensity = 3.0;  // per rc^3

using Factory = std::function<std::shared_ptr<Force>(const State&)>;

Vec3 random_direction(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  Vec3 n;
  do {
    n = Vec3(g(rng), g(rng), g(rng));
  } while (n.norm() < 1e-3);
  return n.normalized();
}

// Particle 0 at `a`, particle 1 at a + r n, at rest, 1 kg each.
State two(const Vec3& a, const Vec3& n, double r) {
  State s = make_state(2);
  s.x.col(0) = a;
  s.x.col(1) = a + r * n;
  return s;
}

const PairReference* reference_of(const Force& f) { return dynamic_cast<const PairReference*>(&f); }

// The cutoff of a freshly built object, or a reason it is unusable.
double usable_cutoff(const PairReference& ref) {
  const double rc = ref.pair_cutoff();
  if (!(rc > 0.0) || !std::isfinite(rc)) {
    throw std::runtime_error(
        fmt::format("pair_cutoff() is {} m (expected a finite cutoff > 0 m)", rc));
  }
  return rc;
}

// Potential energy and radial force (on particle 1, along n: > 0 repulsive)
// of two particles at rest at distance r, each from an object of its own
// state's context.
struct Radial {
  double energy, force;
};
std::optional<Radial> radial(const Factory& make, const Vec3& a, const Vec3& n, double r) {
  const State s = two(a, n, r);
  const auto force = make(s);
  const auto u = force->potential_energy(s.view());
  if (!u) return std::nullopt;
  return Radial{*u, Vec3(forces_of(*force, s).col(1)).dot(n)};
}

CheckResult newton_third_law(const Factory& make, double rc, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double worst = 0.0;
  int trials = 0;
  for (int round = 0; round < 3; ++round) {
    for (const double fraction : kFractions) {
      // A and B with their own velocities and masses, as particles 0 and 1,
      // then as 1 and 0.
      State ab = two(Vec3(u(rng), u(rng), u(rng)), random_direction(rng), fraction * rc);
      for (Index i = 0; i < 2; ++i) {
        ab.v.col(i) = Vec3(u(rng), u(rng), u(rng));
        ab.mass(i) = 1.25 + 0.75 * u(rng);
      }
      State ba = ab;
      for (Index i = 0; i < 2; ++i) {
        ba.x.col(i) = ab.x.col(1 - i);
        ba.v.col(i) = ab.v.col(1 - i);
        ba.mass(i) = ab.mass(1 - i);
      }
      const Matrix3X f1 = forces_of(*make(ab), ab), f2 = forces_of(*make(ba), ba);
      const Vec3 a1 = f1.col(0), b1 = f1.col(1), a2 = f2.col(1), b2 = f2.col(0);
      const double scale = std::max({a1.norm(), a2.norm(), 1e-300});
      worst = std::max(
          {worst, (a1 + b1).norm() / scale, (a2 + b2).norm() / scale, (a1 - a2).norm() / scale});
      ++trials;
    }
  }
  const double bound = 1e-12;
  return result("pair.newton_third_law", worst <= bound, worst, bound,
                fmt::format("{} pairs at 0.4..0.97 rc, random v and m, both labellings: max "
                            "|f_A + f_B|, |f_A(A first) - f_A(B first)| over |f_A|",
                            trials));
}

CheckResult gradient(const Factory& make, double rc, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double h = 1e-5 * rc;
  double worst = 0.0;
  for (int round = 0; round < 2; ++round) {
    for (const double fraction : kFractions) {
      const Vec3 a(u(rng), u(rng), u(rng)), n = random_direction(rng);
      const double r = fraction * rc;
      const auto at = radial(make, a, n, r), up = radial(make, a, n, r + h),
                 down = radial(make, a, n, r - h);
      if (!at || !up || !down) {
        return skip("pair.gradient", "reports no potential energy");
      }
      const double dudr = (up->energy - down->energy) / (2 * h);
      const double scale = std::abs(at->force) + std::abs(at->energy) / r + 1e-300;
      worst = std::max(worst, std::abs(at->force + dudr) / scale);
    }
  }
  const double bound = 1e-6;
  return result("pair.gradient", worst <= bound, worst, bound,
                "two particles at rest at r = 0.4..0.97 rc: |F_r + dU/dr| over |F_r| + |U|/r, "
                "central differences h = 1e-5 rc");
}

// ---- random configurations for pair.matches_brute_force ----

struct Box {
  const char* label;
  Index n;
  std::array<bool, 3> periodic;
};

// n particles in [0, L)^3 no two closer than kMinDistance rc (to the nearest
// image along periodic axes), random sequential addition: at density
// kDensity the spheres of that diameter fill 7% of the box, far from jamming.
bool place(State& s, double rc, std::mt19937_64& rng) {
  const Vec3 length = s.domain.length();
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double dmin2 = kMinDistance * rc * kMinDistance * rc;
  for (Index i = 0; i < s.size(); ++i) {
    bool ok = false;
    for (int attempt = 0; attempt < 10000 && !ok; ++attempt) {
      const Vec3 x = s.domain.min + Vec3(u(rng), u(rng), u(rng)).cwiseProduct(length);
      ok = true;
      for (Index j = 0; j < i && ok; ++j) {
        ok = s.domain.minimum_image(x - Vec3(s.x.col(j))).squaredNorm() >= dmin2;
      }
      if (ok) s.x.col(i) = x;
    }
    if (!ok) return false;
  }
  return true;
}

// Each particle in turn tries a random move of `step` per axis (uniform
// in [-step, step]), kept if no pair comes closer than kMinDistance rc;
// positions are then wrapped into a periodic box, as the kernel does after
// every step.
void move(State& s, double step, double rc, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-step, step);
  const double dmin2 = kMinDistance * rc * kMinDistance * rc;
  for (Index i = 0; i < s.size(); ++i) {
    const Vec3 x = s.domain.wrap(Vec3(s.x.col(i)) + Vec3(u(rng), u(rng), u(rng)));
    bool ok = true;
    for (Index j = 0; j < s.size() && ok; ++j) {
      if (j != i) ok = s.domain.minimum_image(x - Vec3(s.x.col(j))).squaredNorm() >= dmin2;
    }
    if (ok) s.x.col(i) = x;
  }
}

// The all-pairs evaluation, and for each particle sum_j |F_ij| and for the
// energy sum |U_ij|: what rounding in a sum over pairs is relative to. Each
// pair is evaluated alone, by the reference, on a two-particle state.
struct Reference {
  Matrix3X f;
  double energy = 0.0;
  Eigen::VectorXd force_scale;
  double energy_scale = 0.0;
};

// `alone`: the object that evaluates one pair on its own (without special
// bonds, which name the particles of `s`).
Reference reference_sum(const PairReference& ref, const PairReference& alone_ref, const State& s,
                        double rc) {
  Reference out;
  out.f = Matrix3X::Zero(3, s.size());
  out.energy = ref.add_forces_all_pairs(s.view(), out.f);
  out.force_scale = Eigen::VectorXd::Zero(s.size());
  State alone = make_state(2);
  Matrix3X f2(3, 2);
  for (Index i = 0; i < s.size(); ++i) {
    for (Index j = i + 1; j < s.size(); ++j) {
      const Vec3 d = s.domain.minimum_image(s.x.col(i) - s.x.col(j));
      if (!(d.squaredNorm() < rc * rc)) continue;
      alone.x.col(0) = s.x.col(i);
      alone.x.col(1) = Vec3(s.x.col(i)) - d;
      const Index which[2] = {i, j};
      for (Index k = 0; k < 2; ++k) {
        const Index p = which[k];
        alone.v.col(k) = s.v.col(p);
        alone.mass(k) = s.mass(p);
        alone.radius[static_cast<std::size_t>(k)] = s.radius[static_cast<std::size_t>(p)];
      }
      f2.setZero();
      out.energy_scale += std::abs(alone_ref.add_forces_all_pairs(alone.view(), f2));
      out.force_scale(i) += f2.col(0).norm();
      out.force_scale(j) += f2.col(1).norm();
    }
  }
  return out;
}

// One evaluation of `force` at `s` against the all-pairs sum of `ref`:
// raises `worst` (relative to sum_j |F_ij| per particle, sum |U_ij| for the
// energy) and names the place in `where`.
void compare_with_reference(Force& force, const PairReference& ref, const PairReference& alone_ref,
                            const State& s, double rc, const std::string& label, double& worst,
                            std::string& where) {
  const Matrix3X f = forces_of(force, s);
  const auto energy = force.potential_energy(s.view());
  const Reference want = reference_sum(ref, alone_ref, s, rc);
  for (Index i = 0; i < s.size(); ++i) {
    const double e = (Vec3(f.col(i)) - Vec3(want.f.col(i))).norm() /
                     (want.force_scale(i) + std::numeric_limits<double>::min());
    if (e > worst) {
      worst = e;
      where = fmt::format("{}: force on particle {}", label, i);
    }
  }
  if (energy) {
    const double e =
        std::abs(*energy - want.energy) / (want.energy_scale + std::numeric_limits<double>::min());
    if (e > worst) {
      worst = e;
      where = fmt::format("{}: energy", label);
    }
  }
}

// `s` (b.n particles) with random velocities and masses, placed in the box
// holding them at the density, larger if the force refuses it (a cutoff
// plus skin that does not fit a periodic side); and the force made for it.
std::shared_ptr<Force> placed_force(const PluginDescriptor& d, const Params& params, const Box& b,
                                    double rc, State& s, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (Index i = 0; i < s.size(); ++i) {
    s.v.col(i) = Vec3(u(rng), u(rng), u(rng));
    s.mass(i) = 1.25 + 0.75 * u(rng);
  }
  double side = std::cbrt(static_cast<double>(b.n) / kDensity) * rc;
  for (int attempt = 0;; ++attempt) {
    s.domain = Domain{Vec3::Zero(), Vec3::Constant(side), b.periodic};
    if (!place(s, rc, rng)) throw std::runtime_error("could not place the particles");
    try {
      return std::shared_ptr<Force>(d.create_force(params, context_of(s)));
    } catch (const ParamError&) {
      if (attempt == 3 || !s.domain.any_periodic()) throw;
      side *= 1.5;
    }
  }
}

CheckResult matches_brute_force(const PluginDescriptor& d, const Params& params, double rc,
                                std::mt19937_64& rng) {
  const Box boxes[] = {{"open, 40 particles", 40, {false, false, false}},
                       {"open, 150 particles", 150, {false, false, false}},
                       {"periodic, 150 particles", 150, {true, true, true}},
                       {"periodic in x and y, 100 particles", 100, {true, true, false}}};
  // Per configuration: calls separated by small moves (the list is reused),
  // large ones (it must be rebuilt) and a fresh placement (everything moved).
  const double kSmall = 0.005, kLarge = 0.25;  // times rc
  const double moves[] = {kSmall, kLarge, kSmall, kLarge, -1.0, kSmall, kLarge};
  double worst = 0.0;
  std::string where;
  int calls = 0;
  for (const Box& b : boxes) {
    State s = make_state(b.n);
    const auto force = placed_force(d, params, b, rc, s, rng);
    const PairReference* ref = reference_of(*force);
    if (!ref) throw std::runtime_error("a second object offers no PairReference");
    for (std::size_t call = 0; call <= std::size(moves); ++call) {
      compare_with_reference(*force, *ref, *ref, s, rc,
                             fmt::format("{}, call {}", b.label, call + 1), worst, where);
      ++calls;
      if (call == std::size(moves)) break;
      if (moves[call] < 0) {
        if (!place(s, rc, rng)) throw std::runtime_error("could not place the particles");
      } else {
        move(s, moves[call] * rc, rc, rng);
      }
    }
  }
  const double bound = 1e-10;
  return result("pair.matches_brute_force", worst <= bound, worst, bound,
                worst <= bound
                    ? fmt::format("{} calls on 4 random configurations (open, periodic; moves of "
                                  "0.005 and 0.25 rc, a fresh placement): max |f_i - f_i(all "
                                  "pairs)| / sum_j |F_ij|, and the same for U",
                                  calls)
                    : fmt::format("the neighbor-list result differs from the all-pairs sum; "
                                  "worst: {}",
                                  where));
}

// Each particle bonded to its nearest neighbour (to the nearest image): a
// forest of short chains and branches whose 1-2, 1-3 and 1-4 pairs lie
// mostly within the cutoff.
std::vector<IndexPair> nearest_bonds(const State& s) {
  std::vector<IndexPair> bonds;
  for (Index i = 0; i < s.size(); ++i) {
    Index best = -1;
    double best2 = std::numeric_limits<double>::infinity();
    for (Index j = 0; j < s.size(); ++j) {
      const double r2 = s.domain.minimum_image(s.x.col(i) - s.x.col(j)).squaredNorm();
      if (j != i && r2 < best2) {
        best = j;
        best2 = r2;
      }
    }
    if (best >= 0) bonds.push_back({std::min(i, best), std::max(i, best)});
  }
  return bonds;
}

CheckResult special_bonds_check(const PluginDescriptor& d, const Params& params, double rc,
                                std::mt19937_64& rng) {
  const char* name = "pair.special_bonds";
  const Box boxes[] = {{"open, 150 particles", 150, {false, false, false}},
                       {"periodic, 150 particles", 150, {true, true, true}}};
  // Excluded and scaled (LAMMPS's `special_bonds lj 0 0.5 0.25`), and
  // excluded only (`special_bonds fene`, the loop without weights).
  const std::array<double, 3> settings[] = {{0.0, 0.5, 0.25}, {0.0, 1.0, 1.0}};
  double worst = 0.0;
  std::string where;
  int calls = 0;
  for (const Box& b : boxes) {
    State s = make_state(b.n);
    const auto force = placed_force(d, params, b, rc, s, rng);
    auto* target = dynamic_cast<SpecialBondsTarget*>(force.get());
    if (!target) {
      return skip(name,
                  "built against an SDK without special bonds (before 0.10): a scene with "
                  "special_bonds refuses this force");
    }
    const auto alone = std::shared_ptr<Force>(d.create_force(params, context_of(s)));
    const std::vector<IndexPair> bonds = nearest_bonds(s);
    for (const auto& w : settings) {
      target->set_special_bonds(
          std::make_shared<const SpecialBonds>(special_bonds(s.size(), bonds, w)));
      for (int call = 0; call < 3; ++call) {  // the list built, reused, rebuilt
        compare_with_reference(
            *force, *reference_of(*force), *reference_of(*alone), s, rc,
            fmt::format("{}, weights {} {} {}, call {}", b.label, w[0], w[1], w[2], call + 1),
            worst, where);
        ++calls;
        move(s, call == 0 ? 0.005 * rc : 0.25 * rc, rc, rng);
      }
    }
  }
  const double bound = 1e-10;
  return result(name, worst <= bound, worst, bound,
                worst <= bound
                    ? fmt::format("{} calls, open and periodic, each particle bonded to its "
                                  "nearest: weights 0 0.5 0.25 and 0 1 1 for the 1-2, 1-3, 1-4 "
                                  "pairs, max |f_i - f_i(all pairs)| / sum_j |F_ij|, and for U",
                                  calls)
                    : fmt::format("with special bonds the neighbor-list result differs from the "
                                  "all-pairs sum; worst: {}",
                                  where));
}

CheckResult continuous_at_cutoff(const PluginDescriptor& d, const Params& params,
                                 const PairReference& home, std::mt19937_64& rng) {
  const char* name = "pair.continuous_at_cutoff";
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  // Declared by the force, or by the convention of a boolean `shift`.
  Params used = params;
  std::string how = "declared continuous";
  if (!home.continuous_at_cutoff()) {
    const auto spec = std::find_if(d.params.begin(), d.params.end(), [](const ParamSpec& s) {
      return s.name == "shift" && s.type == ParamType::Boolean;
    });
    if (spec == d.params.end()) {
      return skip(name,
                  "energy not declared continuous at the cutoff (a law's "
                  "continuous_at_cutoff(), or a boolean `shift` parameter)");
    }
    used.set("shift", true);
    how = "with shift: true";
  }
  const Factory make = [&](const State& s) {
    return std::shared_ptr<Force>(d.create_force(used, context_of(s)));
  };
  const auto probe = make(two(Vec3::Zero(), Vec3::UnitX(), 1.0));
  const PairReference* ref = reference_of(*probe);
  if (!ref || !ref->continuous_at_cutoff()) {
    return skip(name, "energy not declared continuous at the cutoff, even with shift: true");
  }
  const double rc = usable_cutoff(*ref);
  const double h = 1e-6 * rc;
  // The energy's scale, over the distances the other checks use.
  double energy_scale = 0.0;
  for (const double fraction : kFractions) {
    const auto at = radial(make, Vec3::Zero(), Vec3::UnitZ(), fraction * rc);
    if (!at) return skip(name, "reports no potential energy");
    energy_scale = std::max(energy_scale, std::abs(at->energy));
  }
  double worst = 0.0, bound = 0.0;
  bool pass = true;
  for (int trial = 0; trial < 6; ++trial) {
    const Vec3 a(u(rng), u(rng), u(rng)), n = random_direction(rng);
    const auto in = radial(make, a, n, rc - h), out = radial(make, a, n, rc + h);
    // Continuous: U(rc - h) = F(rc) h + O(h^2), nothing beyond rc.
    const double jump = std::max(std::abs(in->energy), std::abs(out->energy));
    const double allowed = 2 * h * std::abs(in->force) + 1e-9 * energy_scale;
    pass = pass && jump <= allowed;
    worst = std::max(worst, jump);
    bound = std::max(bound, allowed);
  }
  return result(name, pass, worst, bound,
                fmt::format("{}: |U| of two particles at rc -+ 1e-6 rc, J, within 2 h |F| + 1e-9 "
                            "max |U(0.4..0.97 rc)|",
                            how));
}

// Which loop the force runs (PairLoop): a central law that branches at the
// cutoff is correct but slower, and the author may not know the one line
// that changes it. Advice, so a skip with the reason rather than a failure.
CheckResult selecting_loop(const Force& force) {
  const char* name = "pair.selecting_loop";
  const auto* loop = dynamic_cast<const PairLoop*>(&force);
  if (!loop) return skip(name, "built against an SDK that does not report its loop (before 0.10)");
  if (!loop->central_law()) {
    return skip(name, "a general law (it takes the pair): the loop branches at the cutoff");
  }
  if (!loop->selects_beyond_cutoff()) {
    return skip(name,
                "the loop branches at the cutoff: if the law is finite at every r2 > 0 (not a "
                "table indexed by r2), declare `static constexpr bool evaluate_beyond_cutoff = "
                "true;` in it, and the loop selects instead (docs/pairs.md, about 0.7 times the "
                "time on a liquid)");
  }
  return result(name, true, 1.0, 1.0,
                "the law declares evaluate_beyond_cutoff: the loop evaluates it on every listed "
                "pair and selects those within the cutoff (pair.matches_brute_force checks that "
                "the values beyond it are never used)");
}

}  // namespace

void pair_checks(const PluginDescriptor& d, const Params& params, const Force& force,
                 std::mt19937_64& rng, std::vector<CheckResult>& out) {
  const PairReference* home = reference_of(force);
  if (!home) {
    const char* why = "not a pair force (offers no pdyn::PairReference, pdyn/pair.hpp)";
    for (const char* name :
         {"pair.newton_third_law", "pair.gradient", "pair.matches_brute_force",
          "pair.special_bonds", "pair.continuous_at_cutoff", "pair.selecting_loop"}) {
      out.push_back(skip(name, why));
    }
    return;
  }
  const Factory make = [&](const State& s) {
    return std::shared_ptr<Force>(d.create_force(params, context_of(s)));
  };
  guarded(out, "pair.newton_third_law",
          [&] { return newton_third_law(make, usable_cutoff(*home), rng); });
  guarded(out, "pair.gradient", [&] { return gradient(make, usable_cutoff(*home), rng); });
  guarded(out, "pair.matches_brute_force",
          [&] { return matches_brute_force(d, params, usable_cutoff(*home), rng); });
  guarded(out, "pair.special_bonds",
          [&] { return special_bonds_check(d, params, usable_cutoff(*home), rng); });
  guarded(out, "pair.continuous_at_cutoff",
          [&] { return continuous_at_cutoff(d, params, *home, rng); });
  guarded(out, "pair.selecting_loop", [&] { return selecting_loop(force); });
}

}  // namespace pdyn::conformance::detail
