// The solver checks: a Solver plugin is run on small systems of the kit's
// own forces (sample.hpp), where the exact solution is known: deterministic,
// finite on a degenerate system, the declared order of convergence on a
// harmonic oscillator, exact under constant acceleration (order >= 2),
// fixed particles kept, time advanced by exactly h. These are checks of
// Solver::step's contract, so they call it directly, not through a Stepper.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <random>

#include "checks.hpp"
#include "pdyn/host/assembly.hpp"
#include "pdyn/system.hpp"
#include "pdyn/thermo.hpp"
#include "sample.hpp"

namespace pdyn::conformance::detail {

namespace {

const Vec3 kX0(1.0, 0.5, -0.25), kV0(0.0, 0.75, 0.5);

std::unique_ptr<System> oscillator() {
  auto sys = std::make_unique<System>();
  SystemAssembly(*sys).add_particle(kX0, kV0, 1.0);
  SystemAssembly(*sys).add_force(std::make_shared<Anchor>(), "conformance anchor");
  return sys;
}

// Phase-space error of `steps` steps of T/steps on the harmonic oscillator, at T = 1 s.
double oscillator_error(const PluginDescriptor& d, const Params& params, int steps) {
  auto sys = oscillator();
  auto solver = d.create_solver(params, SceneContext{sys->view(), nullptr});
  const double h = 1.0 / steps;
  for (int s = 0; s < steps; ++s) solver->step(*sys, h);
  const double t = sys->time();
  const Vec3 x = kX0 * std::cos(t) + kV0 * std::sin(t);
  const Vec3 v = -kX0 * std::sin(t) + kV0 * std::cos(t);
  return std::sqrt((sys->positions().col(0) - x).squaredNorm() +
                   (sys->velocities().col(0) - v).squaredNorm());
}

// The kit's forces on a random state of the sample size, drawn from `seed`.
std::unique_ptr<System> random_system(std::uint64_t seed) {
  std::mt19937_64 r(seed);
  const State s = random_state(r);
  auto sys = std::make_unique<System>();
  SystemAssembly(*sys).set_particles(s.x, s.v, s.mass, s.fixed);
  SystemAssembly(*sys).add_force(std::make_shared<Anchor>(), "conformance anchor");
  SystemAssembly(*sys).add_force(std::make_shared<Constant>(Vec3(0, 0, -9.81)),
                                 "conformance gravity");
  return sys;
}

// Determinism, and nothing moving or turning NaN where nothing should.
void basic_solver_checks(const PluginDescriptor& d, const Params& params, std::mt19937_64& rng,
                         std::vector<CheckResult>& out) {
  guarded(out, "deterministic", [&] {
    const std::uint64_t seed = rng();
    Eigen::VectorXd a, b;
    for (Eigen::VectorXd* y : {&a, &b}) {
      auto sys = random_system(seed);
      auto solver = d.create_solver(params, SceneContext{sys->view(), nullptr});
      for (int s = 0; s < 20; ++s) solver->step(*sys, 0.01);
      *y = sys->state();
    }
    const bool same = std::memcmp(a.data(), b.data(), sizeof(double) * a.size()) == 0;
    return result("deterministic", same, (a - b).cwiseAbs().maxCoeff(), 0,
                  "20 steps from the same state with two solver objects: bit-identical");
  });

  guarded(out, "finite_on_degenerate", [&] {
    // Coincident particles at rest with no force: nothing may move, nothing may be NaN.
    auto sys = std::make_unique<System>();
    Matrix3X x = Matrix3X::Zero(3, 4);
    x.colwise() = Vec3(1e6, -1e6, 1e6);
    SystemAssembly(*sys).set_particles(x, Matrix3X::Zero(3, 4), Eigen::VectorXd::Ones(4),
                                       std::vector<std::uint8_t>(4, 0));
    auto solver = d.create_solver(params, SceneContext{sys->view(), nullptr});
    for (int s = 0; s < 10; ++s) solver->step(*sys, 0.01);
    const Eigen::VectorXd y = sys->state();
    const Index bad = (y.array().isFinite() == false).count();
    const double drift = (sys->positions() - x).cwiseAbs().maxCoeff();
    return result("finite_on_degenerate", bad == 0 && drift == 0, static_cast<double>(bad) + drift,
                  0,
                  "coincident particles at rest, far from the origin, no force: state finite "
                  "and unchanged");
  });
}

// The declared order, measured; exact under constant acceleration (order >= 2).
void accuracy_checks(const PluginDescriptor& d, const Params& params,
                     std::vector<CheckResult>& out) {
  const int order = d.solver_traits.order;
  guarded(out, "solver.convergence_order", [&] {
    // Halving h multiplies the global error by 2^-p. The coarse step count is
    // chosen so that both errors are far above round-off (1e-10 and more).
    const int n = order >= 3 ? 8 : 64;
    const double e1 = oscillator_error(d, params, n), e2 = oscillator_error(d, params, 2 * n);
    const double measured = std::log2(e1 / e2);
    if (order <= 0) {
      return skip("solver.convergence_order",
                  fmt::format("no declared order; measured {:.2f}", measured));
    }
    return result("solver.convergence_order", std::abs(measured - order) <= 0.3, measured, 0.3,
                  fmt::format("harmonic oscillator to t = 1 s, h = 1/{} and 1/{}: declared order "
                              "{}, |measured - declared| <= bound",
                              n, 2 * n, order));
  });

  if (order >= 2) {
    guarded(out, "solver.exact_constant_acceleration", [&] {
      const Vec3 g(0.3, -0.2, -9.81);
      auto sys = std::make_unique<System>();
      SystemAssembly(*sys).add_particle(kX0, kV0, 2.0);
      SystemAssembly(*sys).add_force(std::make_shared<Constant>(g), "conformance constant");
      auto solver = d.create_solver(params, SceneContext{sys->view(), nullptr});
      for (int s = 0; s < 10; ++s) solver->step(*sys, 0.1);
      const double t = sys->time();
      const Vec3 x = kX0 + kV0 * t + 0.5 * g * t * t, v = kV0 + g * t;
      const double err =
          std::max((sys->positions().col(0) - x).norm(), (sys->velocities().col(0) - v).norm());
      const double bound = 1e-12 * (1.0 + x.norm() + v.norm());
      return result("solver.exact_constant_acceleration", err <= bound, err, bound,
                    "declared order >= 2: 10 steps of 0.1 s under constant g, m and m/s");
    });
  } else {
    out.push_back(skip("solver.exact_constant_acceleration", "declared order < 2"));
  }
}

// Step's contract: fixed particles stay, time advances by exactly h.
void contract_checks(const PluginDescriptor& d, const Params& params, std::mt19937_64& rng,
                     std::vector<CheckResult>& out) {
  guarded(out, "solver.fixed_particles_stay", [&] {
    auto sys = random_system(rng());
    SystemAssembly(*sys).set_fixed(1, true);
    SystemAssembly(*sys).set_fixed(4, true);
    const Matrix3X x0 = sys->positions();
    auto solver = d.create_solver(params, SceneContext{sys->view(), nullptr});
    for (int s = 0; s < 20; ++s) solver->step(*sys, 0.01);
    double moved = 0;
    for (Index i : {Index{1}, Index{4}}) {
      moved = std::max(moved, (sys->positions().col(i) - x0.col(i)).cwiseAbs().maxCoeff());
      moved = std::max(moved, sys->velocities().col(i).cwiseAbs().maxCoeff());
    }
    return result("solver.fixed_particles_stay", moved == 0, moved, 0,
                  "2 fixed of 6 particles, 20 steps: max change of x (m) and v (m/s)");
  });

  guarded(out, "solver.time_advances_by_h", [&] {
    auto sys = random_system(rng());
    sys->set_time(0.3);
    auto solver = d.create_solver(params, SceneContext{sys->view(), nullptr});
    double worst = 0;
    for (int s = 0; s < 20; ++s) {
      const double before = sys->time();
      solver->step(*sys, 0.01);
      worst = std::max(worst, std::abs(sys->time() - (before + 0.01)));
    }
    return result("solver.time_advances_by_h", worst == 0, worst, 0,
                  "20 steps of 0.01 s from t = 0.3 s: |t_after - (t_before + h)|, s");
  });
}

// The kit's periodic liquid: 27 soft spheres on a jittered 3 x 3 x 3 grid
// of 1 m in a periodic 3 m box, 1 kg each, velocities drawn from `seed`.
std::unique_ptr<System> soft_liquid(std::uint64_t seed) {
  std::mt19937_64 r(seed);
  std::uniform_real_distribution<double> jitter(-0.15, 0.15), speed(-1.0, 1.0);
  Matrix3X x(3, 27), v(3, 27);
  Index k = 0;
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) {
      for (int c = 0; c < 3; ++c, ++k) {
        x.col(k) = Vec3(a + 0.5 + jitter(r), b + 0.5 + jitter(r), c + 0.5 + jitter(r));
        v.col(k) = Vec3(speed(r), speed(r), speed(r));
      }
    }
  }
  auto sys = std::make_unique<System>();
  const SystemAssembly assembly(*sys);
  assembly.set_particles(x, v, Eigen::VectorXd::Ones(27), std::vector<std::uint8_t>(27, 0));
  Domain box;
  box.min = Vec3::Zero();
  box.max = Vec3::Constant(3.0);
  box.periodic = {true, true, true};
  assembly.set_domain(box);
  assembly.add_force(std::make_shared<SoftSpheres>(), "conformance soft spheres");
  return sys;
}

// The largest |K + U + reservoir - its start| over 1 s of steps of h on the
// soft liquid (the kernel's wrap after each step, as a host's).
double extended_energy_error(const PluginDescriptor& d, const Params& params, std::uint64_t seed,
                             double h) {
  auto sys = soft_liquid(seed);
  auto solver = d.create_solver(params, SceneContext{sys->view(), nullptr});
  const auto energy = [&] {
    return sys->kinetic_energy() + sys->potential_energy() +
           total_reservoir_energy(*sys, solver.get());
  };
  const double h0 = energy();
  double worst = 0.0;
  for (int s = 0; s < static_cast<int>(std::lround(1.0 / h)); ++s) {
    solver->step(*sys, h);
    SystemAssembly(*sys).wrap_positions();
    worst = std::max(worst, std::abs(energy() - h0));
  }
  return worst;
}

// A solver that is an EnergyReservoir (a thermostat, a barostat) conserves
// K + U + reservoir to its declared order: the largest error over 1 s on
// the kit's periodic liquid, at h = 0.01 s and 0.0025 s. A solver with an
// optional `pressure` (Pa) is a barostat by pdyn's convention
// (nose_hoover's): the check runs again with pressure 1 Pa (and pdamp 0.5 s
// if it takes one), its conserved quantity then holding P V and the
// barostat's energies.
void extended_energy_checks(const PluginDescriptor& d, const Params& params, std::uint64_t seed,
                            std::vector<CheckResult>& out) {
  const auto spec = [&](const char* name) {
    return std::find_if(d.params.begin(), d.params.end(),
                        [&](const ParamSpec& p) { return p.name == name; });
  };
  const auto pressure = spec("pressure");
  const bool barostat = pressure != d.params.end() && !pressure->required &&
                        pressure->type == ParamType::Real && !params.has("pressure");
  for (const bool npt : {false, true}) {
    const char* name = npt ? "solver.extended_energy_npt" : "solver.extended_energy";
    if (npt && !barostat) {
      out.push_back(skip(name, "no optional `pressure` parameter: not a barostat"));
      continue;
    }
    guarded(out, name, [&] {
      Params p = params;
      if (npt) {
        p.set("pressure", 1.0);
        if (spec("pdamp") != d.params.end() && !p.has("pdamp")) p.set("pdamp", 0.5);
      }
      {
        auto probe = soft_liquid(seed);
        auto solver = d.create_solver(p, SceneContext{probe->view(), nullptr});
        if (dynamic_cast<const EnergyReservoir*>(solver.get()) == nullptr) {
          return skip(name, "not an EnergyReservoir (pdyn/thermo.hpp): K + U is its energy");
        }
      }
      const double coarse = extended_energy_error(d, p, seed, 0.01);
      const double fine = extended_energy_error(d, p, seed, 0.0025);
      const double order = std::log2(coarse / fine) / 2.0;
      const int declared = d.solver_traits.order;
      return result(name, std::abs(order - declared) <= 0.4, order, 0.4,
                    fmt::format("K + U + reservoir over 1 s on 27 soft spheres in a periodic box"
                                "{}: largest error {:.3g} J at h = 0.01 s, {:.3g} J at 0.0025 s, "
                                "order {:.2f} (declared {})",
                                npt ? " at pressure 1 Pa" : "", coarse, fine, order, declared));
    });
  }
}

}  // namespace

void solver_checks(const PluginDescriptor& d, const Options& o, std::vector<CheckResult>& out) {
  std::mt19937_64 rng(o.seed);
  const Params params = sample_params(d, kParticles);
  std::unique_ptr<Solver> probe;
  guarded(out, "construct.defaults", [&] {
    auto sys = oscillator();
    probe = d.create_solver(params, SceneContext{sys->view(), nullptr});
    return result("construct.defaults", probe != nullptr, probe ? 1 : 0, 1,
                  probe ? "created with defaults" : "factory returned null");
  });
  if (!probe) return;

  basic_solver_checks(d, params, rng, out);
  accuracy_checks(d, params, out);
  contract_checks(d, params, rng, out);
  extended_energy_checks(d, params, rng(), out);
}

}  // namespace pdyn::conformance::detail
