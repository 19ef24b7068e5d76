// The conformance checks. Every check builds its own small particle system
// from a seeded generator, so a report is reproducible from (plugin, seed).
#include "pdyn/conformance.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <latch>
#include <memory>
#include <random>
#include <thread>

#include "checks.hpp"
#include "isolation.hpp"
#include "pdyn/system.hpp"

namespace pdyn::conformance {

namespace {

constexpr Index kParticles = 6;

// ---- particle configurations ----

struct State {
  Matrix3X x, v, f;
  Eigen::VectorXd mass;
  std::vector<std::uint8_t> fixed;
  double t = 0.0;

  Index size() const { return x.cols(); }
  ParticleView view() const {
    return ParticleView{t, Eigen::Map<const Matrix3X>(x.data(), 3, size()),
                        Eigen::Map<const Matrix3X>(v.data(), 3, size()),
                        Eigen::Map<const Eigen::VectorXd>(mass.data(), size()),
                        std::span<const std::uint8_t>(fixed)};
  }
  MutableParticleView mutable_view() {
    return MutableParticleView{t,
                               Eigen::Map<Matrix3X>(x.data(), 3, size()),
                               Eigen::Map<Matrix3X>(v.data(), 3, size()),
                               Eigen::Map<const Matrix3X>(f.data(), 3, size()),
                               Eigen::Map<const Eigen::VectorXd>(mass.data(), size()),
                               std::span<const std::uint8_t>(fixed)};
  }
};

State make_state(Index n) {
  State s;
  s.x = Matrix3X::Zero(3, n);
  s.v = Matrix3X::Zero(3, n);
  s.f = Matrix3X::Zero(3, n);
  s.mass = Eigen::VectorXd::Ones(n);
  s.fixed.assign(static_cast<std::size_t>(n), 0);
  return s;
}

// Positions in [-1, 1]^3 m, velocities in [-1, 1]^3 m/s, masses in [0.5, 2] kg.
State random_state(std::mt19937_64& rng, Index n = kParticles) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  State s = make_state(n);
  for (Index i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      s.x(k, i) = u(rng);
      s.v(k, i) = u(rng);
    }
    s.mass(i) = 1.25 + 0.75 * u(rng);
  }
  s.t = 0.5 + 0.5 * u(rng);
  return s;
}

// The degenerate configurations of the no-NaN check.
std::vector<std::pair<std::string, State>> degenerate_states(std::mt19937_64& rng) {
  std::vector<std::pair<std::string, State>> out;
  State base = random_state(rng);
  State coincident = base;
  for (Index i = 0; i < coincident.size(); ++i) coincident.x.col(i) = base.x.col(0);
  out.emplace_back("coincident", coincident);
  State coincident_rest = coincident;
  coincident_rest.v.setZero();
  out.emplace_back("coincident at rest", coincident_rest);
  State rest = base;
  rest.v.setZero();
  out.emplace_back("at rest", rest);
  State far = base;
  far.x.colwise() += Vec3(1e6, -1e6, 1e6);
  out.emplace_back("far from the origin (1e6 m)", far);
  return out;
}

// ---- helpers ----

bool bit_equal(const Matrix3X& a, const Matrix3X& b) {
  return a.cols() == b.cols() &&
         std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<std::size_t>(a.size())) == 0;
}

double max_abs(const Matrix3X& m) { return m.size() == 0 ? 0.0 : m.cwiseAbs().maxCoeff(); }

std::size_t non_finite(const Matrix3X& m) {
  std::size_t count = 0;
  for (Index k = 0; k < m.size(); ++k) count += std::isfinite(m.data()[k]) ? 0 : 1;
  return count;
}

CheckResult result(std::string name, bool pass, double measured, double bound, std::string detail) {
  return {std::move(name), pass ? Verdict::Pass : Verdict::Fail, measured, bound,
          std::move(detail)};
}

CheckResult skip(std::string name, std::string why) {
  return {std::move(name), Verdict::Skip, 0.0, 0.0, std::move(why)};
}

// Runs `check`, turning an exception from the plugin into a failed check.
// Isolated (Options::isolate), it tells the parent process which check runs,
// and skips a check that crashed an earlier child, taking its result.
void guarded(std::vector<CheckResult>& out, const std::string& name,
             const std::function<CheckResult()>& check) {
  detail::Worker* worker = detail::current_worker();
  if (worker) {
    if (const CheckResult* recorded = worker->begin(out, name)) {
      out.push_back(*recorded);
      return;
    }
  }
  try {
    out.push_back(check());
  } catch (const std::exception& e) {
    out.push_back(result(name, false, 0, 0, fmt::format("threw: {}", e.what())));
  } catch (...) {
    out.push_back(result(name, false, 0, 0, "threw a non-standard exception"));
  }
  if (worker) worker->flush(out);
}

SceneContext context_of(const State& s) { return SceneContext{s.view(), nullptr}; }

// ---- every kind ----

CheckResult check_descriptor(const PluginDescriptor& d) {
  std::vector<std::string> missing;
  if (d.name.empty()) missing.push_back("name");
  if (d.version.empty()) missing.push_back("version");
  if (d.description.empty()) missing.push_back("description");
  for (const auto& p : d.params) {
    if (p.doc.empty()) missing.push_back(fmt::format("doc of parameter '{}'", p.name));
  }
  return result("descriptor.complete", missing.empty(), static_cast<double>(missing.size()), 0,
                missing.empty() ? "name, version, description and every parameter's doc given"
                                : fmt::format("missing: {}", fmt::join(missing, ", ")));
}

// ---- forces ----

Matrix3X forces_of(Force& force, const State& s) {
  Matrix3X f = Matrix3X::Zero(3, s.size());
  force.add_forces(s.view(), f);
  return f;
}

class DenseSink final : public JacobianSink {
 public:
  explicit DenseSink(Index n) : dfdx(Eigen::MatrixXd::Zero(3 * n, 3 * n)), dfdv(dfdx) {}
  void add_dfdx(Index i, Index j, const Eigen::Matrix3d& b) override {
    dfdx.block<3, 3>(3 * i, 3 * j) += b;
  }
  void add_dfdv(Index i, Index j, const Eigen::Matrix3d& b) override {
    dfdv.block<3, 3>(3 * i, 3 * j) += b;
  }
  Eigen::MatrixXd dfdx, dfdv;
};

void force_checks(const PluginDescriptor& d, const Options& o, std::vector<CheckResult>& out) {
  std::mt19937_64 rng(o.seed);
  const State home = random_state(rng);
  const Params params = sample_params(d, kParticles);
  auto make = [&] { return std::shared_ptr<Force>(d.create_force(params, context_of(home))); };

  std::shared_ptr<Force> force;
  guarded(out, "construct.defaults", [&] {
    force = make();
    return result("construct.defaults", force != nullptr, force ? 1 : 0, 1,
                  force ? "created with defaults and sample values of required parameters"
                        : "factory returned null");
  });
  if (!force) return;

  guarded(out, "deterministic", [&] {
    const Matrix3X a = forces_of(*force, home), b = forces_of(*force, home);
    const Matrix3X c = forces_of(*make(), home);
    const bool same = bit_equal(a, b) && bit_equal(a, c);
    return result("deterministic", same, std::max(max_abs(a - b), max_abs(a - c)), 0,
                  "same state twice, and a second object: bit-identical forces");
  });

  guarded(out, "read_only_state", [&] {
    State s = home;
    const State before = s;
    Matrix3X f = Matrix3X::Zero(3, s.size());
    force->add_forces(s.view(), f);
    (void)force->potential_energy(s.view());
    DenseSink sink(s.size());
    (void)force->add_jacobians(s.view(), sink);
    const bool same = bit_equal(s.x, before.x) && bit_equal(s.v, before.v) &&
                      std::memcmp(s.mass.data(), before.mass.data(),
                                  sizeof(double) * static_cast<std::size_t>(s.size())) == 0;
    return result("read_only_state", same, same ? 0 : 1, 0,
                  "x, v, m unchanged by add_forces, potential_energy, add_jacobians");
  });

  guarded(out, "adds_only", [&] {
    // Another force's contribution is already in f: it must stay there.
    Matrix3X base = Matrix3X::Zero(3, home.size());
    for (Index i = 0; i < base.cols(); ++i) base.col(i) = Vec3(1.0 + i, -2.0, 3.0 - i);
    Matrix3X f = base;
    force->add_forces(home.view(), f);
    const Matrix3X alone = forces_of(*force, home);
    const double err = max_abs(f - base - alone);
    const double bound = 1e-12 * (max_abs(alone) + max_abs(base));
    return result("adds_only", err <= bound, err, bound,
                  "|f(prefilled) - prefill - f(zero)|_max, N");
  });

  guarded(out, "finite_on_degenerate", [&] {
    std::size_t bad = 0;
    std::string where;
    for (const auto& [label, s] : degenerate_states(rng)) {
      const Matrix3X f = forces_of(*force, s);
      std::size_t n = non_finite(f);
      if (const auto u = force->potential_energy(s.view()); u && !std::isfinite(*u)) ++n;
      if (n > 0 && where.empty()) where = label;
      bad += n;
    }
    return result("finite_on_degenerate", bad == 0, static_cast<double>(bad), 0,
                  bad == 0 ? "coincident, at rest, far: no NaN/inf in f or U"
                           : fmt::format("non-finite values, first on: {}", where));
  });

  if (d.force_traits.internal) {
    guarded(out, "force.net_force_zero", [&] {
      double worst = 0, bound = 0;
      for (int trial = 0; trial < 5; ++trial) {
        const State s = trial == 0 ? home : random_state(rng);
        const Matrix3X f = forces_of(*force, s);
        worst = std::max(worst, f.rowwise().sum().norm());
        bound = std::max(bound, 1e-10 * (f.colwise().norm().sum() + 1e-300));
      }
      return result("force.net_force_zero", worst <= bound, worst, bound,
                    "declared internal: |sum f_i|, N, on 5 random states");
    });
    guarded(out, "force.net_torque_zero", [&] {
      double worst = 0, bound = 0;
      for (int trial = 0; trial < 5; ++trial) {
        const State s = trial == 0 ? home : random_state(rng);
        const Matrix3X f = forces_of(*force, s);
        Vec3 torque = Vec3::Zero();
        double scale = 0;
        for (Index i = 0; i < s.size(); ++i) {
          torque += Vec3(s.x.col(i)).cross(Vec3(f.col(i)));
          scale += s.x.col(i).norm() * f.col(i).norm();
        }
        worst = std::max(worst, torque.norm());
        bound = std::max(bound, 1e-10 * (scale + 1e-300));
      }
      return result("force.net_torque_zero", worst <= bound, worst, bound,
                    "declared internal: |sum x_i x f_i|, N m, on 5 random states");
    });
    guarded(out, "force.translation_invariant", [&] {
      State moved = home;
      moved.x.colwise() += Vec3(10.0, -20.0, 30.0);
      const Matrix3X a = forces_of(*force, home), b = forces_of(*force, moved);
      const double err = max_abs(a - b), bound = 1e-9 * (max_abs(a) + 1.0);
      return result("force.translation_invariant", err <= bound, err, bound,
                    "declared internal: |f(x + (10,-20,30) m) - f(x)|_max, N");
    });
  } else {
    out.push_back(skip("force.net_force_zero", "not declared internal"));
  }

  guarded(out, "force.gradient_of_potential", [&] {
    State s = home;
    s.v.setZero();  // damping has no potential: compare the conservative part
    if (!force->potential_energy(s.view())) {
      return skip("force.gradient_of_potential", "reports no potential energy");
    }
    const Matrix3X f = forces_of(*force, s);
    double err = 0;
    for (Index i = 0; i < s.size(); ++i) {
      for (int k = 0; k < 3; ++k) {
        const double x0 = s.x(k, i), h = 1e-5 * std::max(1.0, std::abs(x0));
        s.x(k, i) = x0 + h;
        const double up = *force->potential_energy(s.view());
        s.x(k, i) = x0 - h;
        const double down = *force->potential_energy(s.view());
        s.x(k, i) = x0;
        err = std::max(err, std::abs(f(k, i) + (up - down) / (2 * h)));
      }
    }
    const double bound = 1e-5 * (max_abs(f) + 1.0);
    return result("force.gradient_of_potential", err <= bound, err, bound,
                  "|f + dU/dx (central differences, h = 1e-5 m)|_max, N, at rest");
  });

  guarded(out, "force.jacobians", [&] {
    // At the construction state with v = 0 for df/dx, random v for df/dv:
    // where the approximations implicit solvers allow (e.g. Baraff & Witkin's
    // dropped damping term) vanish, analytic Jacobians must be exact.
    State s = home;
    s.v.setZero();
    DenseSink sink(s.size());
    if (!force->add_jacobians(s.view(), sink)) {
      return skip("force.jacobians", "no analytic Jacobians");
    }
    State sv = home;
    DenseSink sink_v(sv.size());
    force->add_jacobians(sv.view(), sink_v);
    const Index n3 = 3 * s.size();
    Eigen::MatrixXd fdx(n3, n3), fdv(n3, n3);
    for (Index c = 0; c < n3; ++c) {
      const Index i = c / 3;
      const int k = static_cast<int>(c % 3);
      const double h = 1e-6;
      auto column = [&](State& st, Matrix3X& field) {
        const double x0 = field(k, i);
        field(k, i) = x0 + h;
        const Matrix3X up = forces_of(*force, st);
        field(k, i) = x0 - h;
        const Matrix3X down = forces_of(*force, st);
        field(k, i) = x0;
        const Matrix3X diff = (up - down) / (2 * h);
        return Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(diff.data(), n3));
      };
      fdx.col(c) = column(s, s.x);
      fdv.col(c) = column(sv, sv.v);
    }
    const double err = std::max((fdx - sink.dfdx).cwiseAbs().maxCoeff(),
                                (fdv - sink_v.dfdv).cwiseAbs().maxCoeff());
    const double bound =
        1e-5 * (1.0 + std::max(fdx.cwiseAbs().maxCoeff(), fdv.cwiseAbs().maxCoeff()));
    return result("force.jacobians", err <= bound, err, bound,
                  "|df/dx, df/dv - central differences (h = 1e-6)|_max");
  });

  if (d.force_traits.dissipative) {
    guarded(out, "force.dissipative", [&] {
      double worst = -1e300;
      for (int trial = 0; trial < 20; ++trial) {
        const State s = random_state(rng);
        const Matrix3X f = forces_of(*force, s);
        worst = std::max(worst, (f.cwiseProduct(s.v)).sum());
      }
      return result("force.dissipative", worst <= 1e-12, worst, 1e-12,
                    "declared dissipative: max sum f_i . v_i, W, on 20 random states");
    });
  } else {
    out.push_back(skip("force.dissipative", "not declared dissipative"));
  }
}

// ---- solvers ----

// f = -k x (k = 1 N/m) on every particle: with m = 1 kg, x(t) = x0 cos t + v0 sin t.
class Anchor final : public Force {
 public:
  void add_forces(const ParticleView& p, Eigen::Ref<Matrix3X> f) override { f -= p.x; }
  bool add_jacobians(const ParticleView& p, JacobianSink& sink) override {
    for (Index i = 0; i < p.size(); ++i) sink.add_dfdx(i, i, -Eigen::Matrix3d::Identity());
    return true;
  }
  std::optional<double> potential_energy(const ParticleView& p) const override {
    return 0.5 * p.x.squaredNorm();
  }
};

// f = m g, constant.
class Constant final : public Force {
 public:
  explicit Constant(Vec3 g) : g_(std::move(g)) {}
  void add_forces(const ParticleView& p, Eigen::Ref<Matrix3X> f) override {
    f.noalias() += g_ * p.mass.transpose();
  }
  bool add_jacobians(const ParticleView&, JacobianSink&) override { return true; }

 private:
  Vec3 g_;
};

const Vec3 kX0(1.0, 0.5, -0.25), kV0(0.0, 0.75, 0.5);

std::unique_ptr<System> oscillator() {
  auto sys = std::make_unique<System>();
  sys->add_particle(kX0, kV0, 1.0);
  sys->add_force(std::make_shared<Anchor>(), "conformance anchor");
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

  auto random_system = [&](std::uint64_t seed) {
    std::mt19937_64 r(seed);
    const State s = random_state(r);
    auto sys = std::make_unique<System>();
    sys->set_particles(s.x, s.v, s.mass, s.fixed);
    sys->add_force(std::make_shared<Anchor>(), "conformance anchor");
    sys->add_force(std::make_shared<Constant>(Vec3(0, 0, -9.81)), "conformance gravity");
    return sys;
  };

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
    sys->set_particles(x, Matrix3X::Zero(3, 4), Eigen::VectorXd::Ones(4),
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
      sys->add_particle(kX0, kV0, 2.0);
      sys->add_force(std::make_shared<Constant>(g), "conformance constant");
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

  guarded(out, "solver.fixed_particles_stay", [&] {
    auto sys = random_system(rng());
    sys->set_fixed(1, true);
    sys->set_fixed(4, true);
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

// ---- colliders ----
//
// A collider does not describe its obstacle, so the kit finds it through the
// contract of respond(): "puts penetrating particles back on the surface". A
// point is *inside* when respond(), given a particle at rest there, moves it
// (by more than 1e-9 m). The kit probes a grid over [-2, 2]^3 m with that
// test, then drops particles at the inside point nearest the origin from 14
// directions (axes and diagonals) and checks after every step that respond()
// left no particle inside, and that the particle was deflected at all.

constexpr double kInsideTolerance = 1e-9;  // m

bool inside(Collider& c, const Vec3& x) {
  State s = make_state(1);
  s.x.col(0) = x;
  MutableParticleView view = s.mutable_view();
  c.respond(view, 1e-3);
  return (s.x.col(0) - x).norm() > kInsideTolerance;
}

struct Drop {
  Vec3 direction;                   // unit, the direction of travel
  bool hit = false;                 // respond() changed the velocity
  bool ended_inside = false;        // some step ended inside
  Vec3 v_in, v_out, contact_point;  // at the first response
};

Drop drop(Collider& c, const Vec3& target, const Vec3& dir, double speed) {
  Drop r;
  r.direction = dir;
  State s = make_state(1);
  s.x.col(0) = target - 3.0 * dir;
  s.v.col(0) = speed * dir;
  const double h = 0.01;
  for (int step = 0; step < 120; ++step) {
    s.x.col(0) += h * s.v.col(0);
    s.t += h;
    const Vec3 before = s.v.col(0);
    MutableParticleView view = s.mutable_view();
    c.respond(view, h);
    if (!r.hit && (Vec3(s.v.col(0)) - before).norm() > 0) {
      r.hit = true;
      r.v_in = before;
      r.v_out = s.v.col(0);
      r.contact_point = s.x.col(0);
    }
    if (inside(c, s.x.col(0))) r.ended_inside = true;
  }
  return r;
}

std::vector<Vec3> drop_directions() {
  std::vector<Vec3> dirs;
  for (int k = 0; k < 3; ++k) {
    for (double sign : {-1.0, 1.0}) {
      Vec3 d = Vec3::Zero();
      d(k) = sign;
      dirs.push_back(d);
    }
  }
  for (double a : {-1.0, 1.0})
    for (double b : {-1.0, 1.0})
      for (double e : {-1.0, 1.0}) dirs.push_back(Vec3(a, b, e).normalized());
  return dirs;
}

void collider_checks(const PluginDescriptor& d, const Options& o, std::vector<CheckResult>& out) {
  std::mt19937_64 rng(o.seed);
  const State home = random_state(rng);
  Params params = sample_params(d, kParticles);
  // Frictionless, so that the tangential check applies.
  for (const auto& spec : d.params) {
    if (spec.name == "friction" && spec.type == ParamType::Real) params.set("friction", 0.0);
  }
  auto make = [&] {
    return std::shared_ptr<Collider>(d.create_collider(params, context_of(home)));
  };
  std::shared_ptr<Collider> c;
  guarded(out, "construct.defaults", [&] {
    c = make();
    return result("construct.defaults", c != nullptr, c ? 1 : 0, 1,
                  c ? "created with defaults" : "factory returned null");
  });
  if (!c) return;

  guarded(out, "deterministic", [&] {
    State a = random_state(rng);
    a.x *= 0.2;  // near the origin, where default obstacles are
    a.f.setRandom();
    State b = a;
    MutableParticleView va = a.mutable_view(), vb = b.mutable_view();
    c->respond(va, 0.01);
    make()->respond(vb, 0.01);
    const bool same = bit_equal(a.x, b.x) && bit_equal(a.v, b.v);
    return result("deterministic", same, std::max(max_abs(a.x - b.x), max_abs(a.v - b.v)), 0,
                  "respond() of two objects on the same state: bit-identical");
  });

  guarded(out, "read_only_state", [&] {
    State s = home;
    const State before = s;
    Matrix3X f = Matrix3X::Random(3, s.size());
    c->apply_contact_forces(s.view(), f);
    const bool same = bit_equal(s.x, before.x) && bit_equal(s.v, before.v);
    return result("read_only_state", same, same ? 0 : 1, 0,
                  "x, v unchanged by apply_contact_forces");
  });

  guarded(out, "finite_on_degenerate", [&] {
    std::size_t bad = 0;
    for (auto [label, s] : degenerate_states(rng)) {
      (void)label;
      s.f.setConstant(-1.0);
      Matrix3X f = s.f;
      c->apply_contact_forces(s.view(), f);
      MutableParticleView view = s.mutable_view();
      c->respond(view, 0.01);
      bad += non_finite(f) + non_finite(s.x) + non_finite(s.v);
    }
    return result("finite_on_degenerate", bad == 0, static_cast<double>(bad), 0,
                  "coincident, at rest, far: no NaN/inf from respond or contact forces");
  });

  // Find the obstacle.
  std::optional<Vec3> target;
  guarded(out, "collider.obstacle_found", [&] {
    int count = 0;
    for (int i = 0; i <= 16; ++i)
      for (int j = 0; j <= 16; ++j)
        for (int k = 0; k <= 16; ++k) {
          const Vec3 x = Vec3(i, j, k) * 0.25 - Vec3::Constant(2.0);
          if (!inside(*c, x)) continue;
          ++count;
          if (!target || x.norm() < target->norm()) target = x;
        }
    return result("collider.obstacle_found", count > 0, count, 1,
                  "probe points in [-2,2]^3 m (step 0.25) that respond() moves out (>= bound)");
  });
  if (!target) return;

  std::vector<Drop> drops;
  guarded(out, "collider.no_particle_inside", [&] {
    int inside_count = 0, missed = 0, tried = 0;
    for (const Vec3& dir : drop_directions()) {
      if (inside(*c, *target - 3.0 * dir)) continue;  // would start inside
      ++tried;
      drops.push_back(drop(*c, *target, dir, 5.0));
      inside_count += drops.back().ended_inside ? 1 : 0;
      missed += drops.back().hit ? 0 : 1;
    }
    return result("collider.no_particle_inside", inside_count == 0 && missed == 0 && tried > 0,
                  inside_count + missed, 0,
                  fmt::format("{} drops at 5 m/s, h = 0.01 s: {} ended a step inside, {} passed "
                              "through without a response",
                              tried, inside_count, missed));
  });

  // A normal impact: the drop whose velocity came back antiparallel.
  const Drop* normal = nullptr;
  for (const auto& dr : drops) {
    if (dr.hit && dr.v_out.norm() > 0 && dr.v_out.normalized().dot(-dr.direction) > 1 - 1e-12)
      normal = &dr;
    if (normal) break;
  }
  if (!normal) {
    for (const auto& dr : drops) {
      if (dr.hit && dr.v_out.norm() == 0) normal = &dr;  // perfectly inelastic
      if (normal) break;
    }
  }
  if (!normal) {
    out.push_back(
        result("collider.restitution", false, 0, 0, "no axis-aligned drop was a normal impact"));
    return;
  }
  const Vec3 n = -normal->direction;  // outward normal at the contact point

  guarded(out, "collider.restitution", [&] {
    const double e = normal->v_out.norm() / normal->v_in.norm();
    for (const auto& spec : d.params) {
      if (spec.name == "restitution" && spec.type == ParamType::Real) {
        const double kr = params.real("restitution");
        return result(
            "collider.restitution", std::abs(e - kr) <= 1e-9, std::abs(e - kr), 1e-9,
            fmt::format("normal impact at 5 m/s: |v_out|/|v_in| = {:.6g}, declared {}", e, kr));
      }
    }
    return result("collider.restitution", e <= 1.0 + 1e-12, e, 1.0,
                  "normal impact at 5 m/s, no 'restitution' parameter: |v_out|/|v_in| <= bound");
  });

  // The tangential change is measured against the surface normal where each
  // drop hit, which a curved or faceted obstacle (sphere, box) varies: the
  // direction in which respond() puts back a particle at rest just inside
  // that point.
  auto local_normal = [&](const Drop& dr) -> std::optional<Vec3> {
    State s = make_state(1);
    s.x.col(0) = dr.contact_point + 1e-3 * dr.direction;
    const Vec3 before = s.x.col(0);
    MutableParticleView view = s.mutable_view();
    c->respond(view, 1e-3);
    const Vec3 moved = Vec3(s.x.col(0)) - before;
    if (moved.norm() <= kInsideTolerance) return std::nullopt;
    return moved.normalized();
  };
  guarded(out, "collider.frictionless_tangential", [&] {
    double worst = 0;
    int oblique = 0;
    for (const auto& dr : drops) {
      if (!dr.hit) continue;
      const auto m = local_normal(dr);
      if (!m || std::abs(dr.direction.dot(*m)) > 1 - 1e-9 || dr.direction.dot(*m) >= 0) continue;
      ++oblique;
      const Vec3 dv = dr.v_out - dr.v_in;
      worst = std::max(worst, (dv - dv.dot(*m) * *m).norm());
    }
    if (oblique == 0) return skip("collider.frictionless_tangential", "no oblique impact");
    return result(
        "collider.frictionless_tangential", worst <= 1e-12 * 5.0, worst, 1e-12 * 5.0,
        fmt::format("{} oblique impacts at 5 m/s: |tangential change of v|, m/s", oblique));
  });

  guarded(out, "collider.contact_force_normal_only", [&] {
    // A particle at rest on the surface where the normal impact happened.
    State s = make_state(1);
    s.x.col(0) = normal->contact_point;
    const Vec3 t = n.unitOrthogonal();
    double worst = 0;
    for (double push : {-1.0, 1.0}) {
      Matrix3X f(3, 1);
      f.col(0) = 10.0 * push * n + 3.0 * t;
      const Vec3 expected = push < 0 ? Vec3(3.0 * t) : Vec3(f.col(0));
      c->apply_contact_forces(s.view(), f);
      worst = std::max(worst, (Vec3(f.col(0)) - expected).norm());
    }
    return result("collider.contact_force_normal_only", worst <= 1e-12 * 10.0, worst, 1e-12 * 10.0,
                  "resting on the surface: pushing 10 N in + 3 N along -> 3 N along; pulling "
                  "unchanged; error, N");
  });
}

// ---- every kind: two threads, two systems ----
//
// Scenes are independent, so a host may run two of them at once (a parameter
// sweep, a GUI next to a batch run). A plugin that keeps mutable state outside
// its objects (a static scratch buffer, a global cache) breaks that silently.
// Each run builds its own System and plugin object from its own seed; the two
// seeds differ so that shared state shows up as a difference.

constexpr int kThreadSteps = 100;
constexpr double kThreadStep = 0.005;  // s
constexpr int kThreadRounds = 3;

Eigen::VectorXd separate_run(const PluginDescriptor& d, const Params& params, std::uint64_t seed) {
  std::mt19937_64 r(seed);
  State s = random_state(r);
  if (d.kind == PluginKind::Collider) s.x *= 0.5;  // near the origin, where default obstacles are
  auto sys = std::make_unique<System>();
  sys->set_particles(s.x, s.v, s.mass, s.fixed);
  const SceneContext ctx{sys->view(), nullptr};
  // Forces and colliders are stepped with symplectic Euler, the kit's own.
  auto kit_step = [&] {
    const Matrix3X& a = sys->compute_accelerations();
    sys->velocities() += kThreadStep * a;
    sys->positions() += kThreadStep * sys->velocities();
    sys->set_time(sys->time() + kThreadStep);
  };
  switch (d.kind) {
    case PluginKind::Force:
      sys->add_force(std::shared_ptr<Force>(d.create_force(params, ctx)), "under test");
      for (int k = 0; k < kThreadSteps; ++k) kit_step();
      break;
    case PluginKind::Solver: {
      sys->add_force(std::make_shared<Anchor>(), "conformance anchor");
      sys->add_force(std::make_shared<Constant>(Vec3(0, 0, -9.81)), "conformance gravity");
      auto solver = d.create_solver(params, ctx);
      for (int k = 0; k < kThreadSteps; ++k) solver->step(*sys, kThreadStep);
      break;
    }
    case PluginKind::Collider:
      sys->add_force(std::make_shared<Constant>(Vec3(0.5, -0.3, -9.81)), "conformance gravity");
      sys->add_collider(std::shared_ptr<Collider>(d.create_collider(params, ctx)), "under test");
      for (int k = 0; k < kThreadSteps; ++k) {
        kit_step();
        sys->respond_to_collisions(kThreadStep);
      }
      break;
  }
  return sys->state();
}

bool bit_equal(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return a.size() == b.size() &&
         std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<std::size_t>(a.size())) == 0;
}

CheckResult check_threads(const PluginDescriptor& d, const Options& o) {
  const Params params = sample_params(d, kParticles);
  const std::uint64_t seeds[2] = {o.seed * 7919 + 101, o.seed * 7919 + 202};
  const Eigen::VectorXd expected[2] = {separate_run(d, params, seeds[0]),
                                       separate_run(d, params, seeds[1])};
  int differing = 0;
  double worst = 0;
  for (int round = 0; round < kThreadRounds; ++round) {
    Eigen::VectorXd got[2];
    std::exception_ptr error[2];
    std::latch start(2);  // both runs begin together, so that they overlap
    {
      std::jthread threads[2];
      for (int k = 0; k < 2; ++k) {
        threads[k] = std::jthread([&, k] {
          start.arrive_and_wait();
          try {
            got[k] = separate_run(d, params, seeds[k]);
          } catch (...) {
            error[k] = std::current_exception();
          }
        });
      }
    }
    for (const auto& e : error) {
      if (e) std::rethrow_exception(e);
    }
    for (int k = 0; k < 2; ++k) {
      if (bit_equal(got[k], expected[k])) continue;
      ++differing;
      worst = std::max(worst, got[k].size() == expected[k].size()
                                  ? (got[k] - expected[k]).cwiseAbs().maxCoeff()
                                  : std::numeric_limits<double>::infinity());
    }
  }
  return result("threads.two_systems", differing == 0, worst, 0,
                differing == 0
                    ? fmt::format("{} rounds of two threads, each with its own system and object, "
                                  "{} steps of {} s: states bit-identical to one thread's",
                                  kThreadRounds, kThreadSteps, kThreadStep)
                    : fmt::format("{} of {} concurrent runs differ from the same run alone "
                                  "(max |difference| of the state): shared mutable state?",
                                  differing, 2 * kThreadRounds));
}

}  // namespace

const char* verdict_name(Verdict v) {
  switch (v) {
    case Verdict::Pass:
      return "pass";
    case Verdict::Fail:
      return "FAIL";
    case Verdict::Skip:
      return "skip";
  }
  return "?";
}

Params sample_params(const PluginDescriptor& d, Index n) {
  Params p;
  for (const auto& s : d.params) {
    if (s.sample) {
      p.set(s.name, *s.sample);
      continue;
    }
    if (s.fallback) {
      p.set(s.name, *s.fallback);
      continue;
    }
    if (!s.required) continue;
    // A number inside the declared range, preferring 1.
    double x = 1.0;
    if (s.min && x <= *s.min) x = *s.min + 1.0;
    if (s.max && x > *s.max) x = s.min ? 0.5 * (*s.min + *s.max) : *s.max - 1.0;
    switch (s.type) {
      case ParamType::Real:
        p.set(s.name, x);
        break;
      case ParamType::Integer:
        p.set(s.name, static_cast<std::int64_t>(std::ceil(x)));
        break;
      case ParamType::Boolean:
        p.set(s.name, false);
        break;
      case ParamType::String:
        p.set(s.name, std::string{});
        break;
      case ParamType::Vector:
        p.set(s.name, Vec3(0.3, -0.2, 0.9));
        break;
      case ParamType::RealList:
        p.set(s.name, std::vector<double>{x});
        break;
      case ParamType::VectorList:
        p.set(s.name, std::vector<Vec3>{Vec3(0.3, -0.2, 0.9)});
        break;
      case ParamType::IndexList:
        p.set(s.name, std::vector<Index>{0, 1, n - 1});
        break;
      case ParamType::IndexPairs:
        p.set(s.name, std::vector<IndexPair>{{0, 1}, {1, 2}, {2, 3}, {0, n - 1}});
        break;
      case ParamType::IndexTriples:
        p.set(s.name, std::vector<IndexTriple>{{0, 1, 2}, {1, 2, 3}});
        break;
      case ParamType::StringList:
        p.set(s.name, std::vector<std::string>{"1"});
        break;
      case ParamType::NamedReals:
        p.set(s.name, NamedReals{{"a", x}});
        break;
    }
  }
  return p;
}

namespace {

void check_sequence(const PluginDescriptor& d, const Options& o, std::vector<CheckResult>& out) {
  out.push_back(check_descriptor(d));
  try {
    switch (d.kind) {
      case PluginKind::Force:
        force_checks(d, o, out);
        break;
      case PluginKind::Solver:
        solver_checks(d, o, out);
        break;
      case PluginKind::Collider:
        collider_checks(d, o, out);
        break;
    }
    // Only for a plugin that can be built at all: the rest would fail for
    // the same reason as construct.defaults.
    const bool constructed = std::any_of(out.begin(), out.end(), [](const CheckResult& r) {
      return r.name == "construct.defaults" && r.verdict == Verdict::Pass;
    });
    if (constructed) {
      guarded(out, "params.bad_rejected", [&] {
        std::mt19937_64 rng(o.seed);
        return detail::check_bad_params(d, sample_params(d, kParticles), random_state(rng).x);
      });
      guarded(out, "threads.two_systems", [&] { return check_threads(d, o); });
    }
  } catch (const std::exception& e) {
    out.push_back(result("run", false, 0, 0, fmt::format("threw: {}", e.what())));
  }
}

}  // namespace

std::vector<CheckResult> run_checks(const PluginDescriptor& d, const Options& o) {
  if (o.isolate) {
    return detail::run_isolated([&](std::vector<CheckResult>& out) { check_sequence(d, o, out); },
                                o.timeout);
  }
  std::vector<CheckResult> out;
  check_sequence(d, o, out);
  return out;
}

bool all_passed(const std::vector<CheckResult>& results) {
  return std::none_of(results.begin(), results.end(),
                      [](const CheckResult& r) { return r.verdict == Verdict::Fail; });
}

std::string table(const std::vector<CheckResult>& results) {
  std::size_t w = 5;
  for (const auto& r : results) w = std::max(w, r.name.size());
  std::string s = fmt::format("{:<{}}  {:<7} {:>11} {:>11}  {}\n", "CHECK", w, "VERDICT",
                              "MEASURED", "BOUND", "DETAIL");
  for (const auto& r : results) {
    if (r.verdict == Verdict::Skip) {
      s += fmt::format("{:<{}}  {:<7} {:>11} {:>11}  {}\n", r.name, w, verdict_name(r.verdict), "-",
                       "-", r.detail);
    } else {
      s += fmt::format("{:<{}}  {:<7} {:>11.3g} {:>11.3g}  {}\n", r.name, w,
                       verdict_name(r.verdict), r.measured, r.bound, r.detail);
    }
  }
  return s;
}

namespace {
std::string xml_escape(const std::string& in) {
  std::string out;
  for (char ch : in) {
    switch (ch) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += ch;
    }
  }
  return out;
}
}  // namespace

std::string junit_xml(const PluginDescriptor& d, const std::vector<CheckResult>& results) {
  const auto failures = std::count_if(results.begin(), results.end(),
                                      [](const auto& r) { return r.verdict == Verdict::Fail; });
  const auto skipped = std::count_if(results.begin(), results.end(),
                                     [](const auto& r) { return r.verdict == Verdict::Skip; });
  std::string s = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  s += fmt::format(
      "<testsuite name=\"pdyn.check.{}\" tests=\"{}\" failures=\"{}\" skipped=\"{}\">\n",
      xml_escape(d.name), results.size(), failures, skipped);
  for (const auto& r : results) {
    s += fmt::format("  <testcase classname=\"{}.{}\" name=\"{}\"", kind_name(d.kind),
                     xml_escape(d.name), xml_escape(r.name));
    const std::string text =
        fmt::format("measured {:.6g}, bound {:.6g}: {}", r.measured, r.bound, r.detail);
    if (r.verdict == Verdict::Fail) {
      s += fmt::format(">\n    <failure message=\"{}\"/>\n  </testcase>\n", xml_escape(text));
    } else if (r.verdict == Verdict::Skip) {
      s += fmt::format(">\n    <skipped message=\"{}\"/>\n  </testcase>\n", xml_escape(r.detail));
    } else {
      s += "/>\n";
    }
  }
  return s + "</testsuite>\n";
}

}  // namespace pdyn::conformance
