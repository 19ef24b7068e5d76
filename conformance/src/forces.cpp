// The force checks: what every Force plugin must do (deterministic, read-only
// on the state, adding only, finite on degenerate configurations) and what
// its descriptor and methods claim (internal: zero net force and torque,
// translation invariance; f = -grad U; analytic Jacobians; dissipative;
// independence of velocity or time; periodic invariance;
// and, for a pair force, the pair.* checks of pairs.cpp).
#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <memory>
#include <pdyn/local_force.hpp>
#include <pdyn/pair.hpp>
#include <pdyn/periodic_invariant.hpp>
#include <random>

#include "checks.hpp"
#include "sample.hpp"

namespace pdyn::conformance::detail {

namespace {

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

}  // namespace

namespace {

// What each group of force checks gets: the plugin, the object made with
// the sample parameters, its home state, and the one random sequence the
// groups draw from in turn (so a seed gives the same states as ever).
struct ForceCase {
  const PluginDescriptor& d;
  std::mt19937_64& rng;
  const State& home;
  Force& force;
  std::function<std::shared_ptr<Force>()> make;  // a second object, same parameters
};

// Determinism, a read-only state, adding into f, finite values.
void basic_checks(ForceCase& c, std::vector<CheckResult>& out) {
  guarded(out, "deterministic", [&] {
    const Matrix3X a = forces_of(c.force, c.home), b = forces_of(c.force, c.home);
    const Matrix3X other = forces_of(*c.make(), c.home);
    const bool same = bit_equal(a, b) && bit_equal(a, other);
    return result("deterministic", same, std::max(max_abs(a - b), max_abs(a - other)), 0,
                  "same state twice, and a second object: bit-identical forces");
  });

  guarded(out, "read_only_state", [&] {
    State s = c.home;
    const State before = s;
    Matrix3X f = Matrix3X::Zero(3, s.size());
    c.force.add_forces(s.view(), f);
    (void)c.force.potential_energy(s.view());
    DenseSink sink(s.size());
    (void)c.force.add_jacobians(s.view(), sink);
    const bool same = bit_equal(s.x, before.x) && bit_equal(s.v, before.v) &&
                      std::memcmp(s.mass.data(), before.mass.data(),
                                  sizeof(double) * static_cast<std::size_t>(s.size())) == 0;
    return result("read_only_state", same, same ? 0 : 1, 0,
                  "x, v, m unchanged by add_forces, potential_energy, add_jacobians");
  });

  guarded(out, "adds_only", [&] {
    // Another force's contribution is already in f: it must stay there.
    Matrix3X base = Matrix3X::Zero(3, c.home.size());
    for (Index i = 0; i < base.cols(); ++i) base.col(i) = Vec3(1.0 + i, -2.0, 3.0 - i);
    Matrix3X f = base;
    c.force.add_forces(c.home.view(), f);
    const Matrix3X alone = forces_of(c.force, c.home);
    const double err = max_abs(f - base - alone);
    const double bound = 1e-12 * (max_abs(alone) + max_abs(base));
    return result("adds_only", err <= bound, err, bound,
                  "|f(prefilled) - prefill - f(zero)|_max, N");
  });

  guarded(out, "finite_on_degenerate", [&] {
    std::size_t bad = 0;
    std::string where;
    for (const auto& [label, s] : degenerate_states(c.rng)) {
      if (c.d.force_traits.singular && label.rfind("coincident", 0) == 0) continue;
      const Matrix3X f = forces_of(c.force, s);
      std::size_t n = non_finite(f);
      if (const auto u = c.force.potential_energy(s.view()); u && !std::isfinite(*u)) ++n;
      if (n > 0 && where.empty()) where = label;
      bad += n;
    }
    return result("finite_on_degenerate", bad == 0, static_cast<double>(bad), 0,
                  bad == 0 ? (c.d.force_traits.singular
                                  ? "at rest, far (declared singular: not coincident): no "
                                    "NaN/inf in f or U"
                                  : "coincident, at rest, far: no NaN/inf in f or U")
                           : fmt::format("non-finite values, first on: {}", where));
  });
}

// Newton's third law and translation invariance, for forces declared internal.
void internal_checks(ForceCase& c, std::vector<CheckResult>& out) {
  if (c.d.force_traits.internal) {
    guarded(out, "force.net_force_zero", [&] {
      double worst = 0, bound = 0;
      for (int trial = 0; trial < 5; ++trial) {
        const State s = trial == 0 ? c.home : random_state(c.rng);
        const Matrix3X f = forces_of(c.force, s);
        worst = std::max(worst, f.rowwise().sum().norm());
        bound = std::max(bound, 1e-10 * (f.colwise().norm().sum() + 1e-300));
      }
      return result("force.net_force_zero", worst <= bound, worst, bound,
                    "declared internal: |sum f_i|, N, on 5 random states");
    });
    guarded(out, "force.net_torque_zero", [&] {
      double worst = 0, bound = 0;
      for (int trial = 0; trial < 5; ++trial) {
        const State s = trial == 0 ? c.home : random_state(c.rng);
        const Matrix3X f = forces_of(c.force, s);
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
      State moved = c.home;
      moved.x.colwise() += Vec3(10.0, -20.0, 30.0);
      const Matrix3X a = forces_of(c.force, c.home), b = forces_of(c.force, moved);
      const double err = max_abs(a - b), bound = 1e-9 * (max_abs(a) + 1.0);
      return result("force.translation_invariant", err <= bound, err, bound,
                    "declared internal: |f(x + (10,-20,30) m) - f(x)|_max, N");
    });
  } else {
    out.push_back(skip("force.net_force_zero", "not declared internal"));
  }
}

// f = -grad U and analytic Jacobians, each against central differences.
void derivative_checks(ForceCase& c, std::vector<CheckResult>& out) {
  guarded(out, "force.gradient_of_potential", [&] {
    State s = c.home;
    s.v.setZero();  // damping has no potential: compare the conservative part
    if (!c.force.potential_energy(s.view())) {
      return skip("force.gradient_of_potential", "reports no potential energy");
    }
    const Matrix3X f = forces_of(c.force, s);
    double err = 0;
    for (Index i = 0; i < s.size(); ++i) {
      for (int k = 0; k < 3; ++k) {
        const double x0 = s.x(k, i), h = 1e-5 * std::max(1.0, std::abs(x0));
        s.x(k, i) = x0 + h;
        const double up = *c.force.potential_energy(s.view());
        s.x(k, i) = x0 - h;
        const double down = *c.force.potential_energy(s.view());
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
    State s = c.home;
    s.v.setZero();
    DenseSink sink(s.size());
    if (!c.force.add_jacobians(s.view(), sink)) {
      return skip("force.jacobians", "no analytic Jacobians");
    }
    State sv = c.home;
    DenseSink sink_v(sv.size());
    c.force.add_jacobians(sv.view(), sink_v);
    const Index n3 = 3 * s.size();
    Eigen::MatrixXd fdx(n3, n3), fdv(n3, n3);
    for (Index col = 0; col < n3; ++col) {
      const Index i = col / 3;
      const int k = static_cast<int>(col % 3);
      const double h = 1e-6;
      auto column = [&](State& st, Matrix3X& field) {
        const double x0 = field(k, i);
        field(k, i) = x0 + h;
        const Matrix3X up = forces_of(c.force, st);
        field(k, i) = x0 - h;
        const Matrix3X down = forces_of(c.force, st);
        field(k, i) = x0;
        const Matrix3X diff = (up - down) / (2 * h);
        return Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(diff.data(), n3));
      };
      fdx.col(col) = column(s, s.x);
      fdv.col(col) = column(sv, sv.v);
    }
    const double err = std::max((fdx - sink.dfdx).cwiseAbs().maxCoeff(),
                                (fdv - sink_v.dfdv).cwiseAbs().maxCoeff());
    const double bound =
        1e-5 * (1.0 + std::max(fdx.cwiseAbs().maxCoeff(), fdv.cwiseAbs().maxCoeff()));
    return result("force.jacobians", err <= bound, err, bound,
                  "|df/dx, df/dv - central differences (h = 1e-6)|_max");
  });
}

// What a local force declares: that it may be added range by range, and
// its linear law.
void local_checks(ForceCase& c, std::vector<CheckResult>& out) {
  LocalForce* local = local_force(c.force);
  // The kernel adds a local force range by range inside its gather pass:
  // that must give add_forces' bits, however the particles are split.
  if (local != nullptr && local->acts_locally()) {
    guarded(out, "force.local_range", [&] {
      const Matrix3X whole = forces_of(c.force, c.home);
      double worst = 0.0;
      const Index n = c.home.size();
      for (const Index cut : {Index{1}, n / 3, n - 1}) {
        Matrix3X f = Matrix3X::Zero(3, n);
        local->add_forces_range(c.home.view(), f, cut, n);
        local->add_forces_range(c.home.view(), f, 0, cut);
        worst = std::max(worst, bits_apart(f, whole));
      }
      return result("force.local_range", worst == 0.0, worst, 0,
                    "add_forces_range over [cut, N) then [0, cut), 3 cuts: add_forces' bits");
    });
  } else {
    out.push_back(skip("force.local_range", "no LocalForce interface"));
  }

  // The kernel evaluates a linear local force's declared law in place of
  // add_forces_range, onto the forces already there: the same bits.
  LinearLocalLaw law;
  LinearLocalForce* linear = linear_local_force(c.force);
  if (linear != nullptr && local != nullptr && local->acts_locally() && linear->linear_law(law)) {
    guarded(out, "force.linear_law", [&] {
      double worst = 0.0;
      for (int trial = 0; trial < 3; ++trial) {
        const State s = trial == 0 ? c.home : random_state(c.rng);
        const Matrix3X before = random_state(c.rng).v;  // forces already there, N
        Matrix3X by_plugin = before, by_law = before;
        local->add_forces_range(s.view(), by_plugin, 0, s.size());
        for (Index i = 0; i < s.size(); ++i) {
          apply_linear_law(law, s.mass(i), s.v.col(i).data(), by_law(0, i), by_law(1, i),
                           by_law(2, i));
        }
        worst = std::max(worst, bits_apart(by_law, by_plugin));
      }
      return result("force.linear_law", worst == 0.0, worst, 0,
                    "the declared law onto random forces, 3 states: add_forces_range's bits");
    });
  } else {
    out.push_back(skip("force.linear_law", "no linear law declared"));
  }
}

// What the force declares: dissipation, independence of velocity or time,
// local action range by range.
void claim_checks(ForceCase& c, std::vector<CheckResult>& out) {
  if (c.d.force_traits.dissipative) {
    guarded(out, "force.dissipative", [&] {
      double worst = -1e300;
      for (int trial = 0; trial < 20; ++trial) {
        const State s = random_state(c.rng);
        const Matrix3X f = forces_of(c.force, s);
        worst = std::max(worst, (f.cwiseProduct(s.v)).sum());
      }
      return result("force.dissipative", worst <= 1e-12, worst, 1e-12,
                    "declared dissipative: max sum f_i . v_i, W, on 20 random states");
    });
  } else {
    out.push_back(skip("force.dissipative", "not declared dissipative"));
  }

  // A claim of independence lets a solver reuse forces evaluated at other
  // velocities or another time (verlet): it must hold bit for bit.
  const StateDependence claim = c.force.dependence();
  if (!claim.velocity || !claim.time) {
    guarded(out, "force.dependence", [&] {
      const Matrix3X f0 = forces_of(c.force, c.home);
      double worst = 0.0;
      for (int trial = 0; trial < 5; ++trial) {
        State s = c.home;
        if (!claim.velocity) s.v = random_state(c.rng).v;
        if (!claim.time) s.t = c.home.t + 1.0 + trial;
        const Matrix3X f = forces_of(c.force, s);
        worst = std::max(worst, bits_apart(f, f0));
      }
      const char* what = claim.velocity ? "time: the same bits at 5 other times"
                         : claim.time   ? "velocity: the same bits at 5 other velocities"
                                        : "velocity and time: the same bits at 5 other "
                                          "velocities and times";
      return result("force.dependence", worst == 0.0, worst, 0,
                    fmt::format("declared independent of {}", what));
    });
  } else {
    out.push_back(skip("force.dependence", "declares it depends on velocity and time"));
  }

  local_checks(c, out);
}

// A force that declares itself periodic-invariant gives the same forces, to
// rounding, when half the particles are moved by whole box lengths, as the
// wrap after a step moves them (velocity Verlet then keeps the forces it
// evaluated before the wrap). In a periodic box of side L = max(2.5, 3 rc +
// 1) m around the kit's particles, rc a pair force's cutoff.
void periodic_check(const PluginDescriptor& d, const Params& params, ForceCase& c,
                    std::vector<CheckResult>& out) {
  const char* name = "force.periodic_invariant";
  if (!periodic_invariant(c.force)) {
    out.push_back(skip(name, "not declared periodic-invariant (pdyn/periodic_invariant.hpp)"));
    return;
  }
  guarded(out, name, [&] {
    const auto* pair = dynamic_cast<const PairReference*>(&c.force);
    const double length = std::max(2.5, pair ? 3.0 * pair->pair_cutoff() + 1.0 : 0.0);
    State inside = c.home;
    inside.domain.min = Vec3::Constant(-0.5 * length);
    inside.domain.max = Vec3::Constant(0.5 * length);
    inside.domain.periodic = {true, true, true};
    State shifted = inside;
    std::uniform_int_distribution<int> axis(0, 2), sign(0, 1);
    for (Index i = 0; i < shifted.size(); i += 2) {
      shifted.x(axis(c.rng), i) += sign(c.rng) ? length : -length;
    }
    const std::shared_ptr<Force> a(d.create_force(params, context_of(inside)));
    const std::shared_ptr<Force> b(d.create_force(params, context_of(shifted)));
    const Matrix3X fa = forces_of(*a, inside), fb = forces_of(*b, shifted);
    const double err = max_abs(fa - fb), bound = 1e-9 * (1.0 + max_abs(fa));
    return result(name, err <= bound, err, bound,
                  fmt::format("|f(x + whole box lengths) - f(x)|_max, N, half the particles moved "
                              "by +-{:g} m in a periodic box",
                              length));
  });
}

}  // namespace

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

  ForceCase c{d, rng, home, *force, make};
  basic_checks(c, out);
  internal_checks(c, out);
  derivative_checks(c, out);
  claim_checks(c, out);
  periodic_check(d, params, c, out);
  pair_checks(d, params, *force, rng, out);
  bonded_checks(d, params, *force, rng, out);
}

}  // namespace pdyn::conformance::detail
