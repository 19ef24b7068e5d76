// The constraint checks (pdyn/constraint.hpp): what every Constraint plugin
// must do (a well-formed pattern, deterministic, read-only on the state,
// finite when particles coincide) and what its values claim, each against
// finite differences of C itself: the Jacobian dC/dx, the rate c_t = dC/dt
// at fixed positions, and the bias b = Cddot - J a along the straight motion
// x(t) = x + v t (a = 0); and that it is satisfied where it was created, as
// a constraint whose geometry is taken from the initial positions must be.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>

#include "checks.hpp"
#include "pdyn/constraint.hpp"
#include "sample.hpp"

namespace pdyn::conformance::detail {

namespace {

// Random states each derivative check runs on, besides the home state.
constexpr int kRandomStates = 4;
// |C| at creation, relative to the state's length scale max(1 m, |x|max).
constexpr double kSatisfiedBound = 1e-9;
// Central differences in x and in t: relative steps, and the bound on the
// error relative to 1 + the largest difference quotient.
constexpr double kFirstStep = 1e-6;
constexpr double kFirstBound = 1e-6;
// Second differences along x + v t: the step (s, for |v| <= 1 m/s per 1 m of
// length scale) and the bound on the error relative to 1 + |b_fd|max.
constexpr double kSecondStep = 1e-4;
constexpr double kSecondBound = 1e-4;

// ---- evaluating a constraint as the kernel does ----

// What `c` writes at `s`, sized from its pattern as the kernel sizes it,
// rate and bias zeroed; value and Jacobian are NaN until the plugin writes
// them (the kernel does not clear them: an entry left unwritten would keep
// a stale value there). Throws if evaluate resized a member.
ConstraintValues values_at(const Constraint& c, const ConstraintPattern& pat, const State& s) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  ConstraintValues v;
  v.value = Eigen::VectorXd::Constant(pat.rows(), nan);
  v.rate = Eigen::VectorXd::Zero(pat.rows());
  v.bias = Eigen::VectorXd::Zero(pat.rows());
  v.jacobian = Matrix3X::Constant(3, pat.entries(), nan);
  c.evaluate(s.view(), v);
  if (v.value.size() != pat.rows() || v.rate.size() != pat.rows() || v.bias.size() != pat.rows() ||
      v.jacobian.rows() != 3 || v.jacobian.cols() != pat.entries()) {
    throw std::runtime_error(
        fmt::format("evaluate resized its values (expected {} rows and {} Jacobian entries, as "
                    "its pattern says)",
                    pat.rows(), pat.entries()));
  }
  return v;
}

Eigen::VectorXd value_at(const Constraint& c, const ConstraintPattern& pat, const State& s) {
  return values_at(c, pat, s).value;
}

// The Jacobian as a dense rows x 3N matrix.
Eigen::MatrixXd dense_jacobian(const ConstraintPattern& pat, const Matrix3X& jac, Index n) {
  Eigen::MatrixXd j = Eigen::MatrixXd::Zero(pat.rows(), 3 * n);
  for (Index r = 0; r < pat.rows(); ++r) {
    for (Index e = pat.row_begin[r]; e < pat.row_begin[r + 1]; ++e) {
      j.block(r, 3 * pat.particle[e], 1, 3) += jac.col(e).transpose();
    }
  }
  return j;
}

// dC/dx by central differences, rows x 3N, at fixed t.
Eigen::MatrixXd jacobian_fd(const Constraint& c, const ConstraintPattern& pat, const State& at) {
  State s = at;
  Eigen::MatrixXd j(pat.rows(), 3 * s.size());
  for (Index i = 0; i < s.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      const double x0 = s.x(k, i), h = kFirstStep * std::max(1.0, std::abs(x0));
      s.x(k, i) = x0 + h;
      const Eigen::VectorXd up = value_at(c, pat, s);
      s.x(k, i) = x0 - h;
      const Eigen::VectorXd down = value_at(c, pat, s);
      s.x(k, i) = x0;
      j.col(3 * i + k) = (up - down) / (2 * h);
    }
  }
  return j;
}

// max |m_ij| of a dense matrix or vector, 0 when empty.
template <class M>
double largest(const M& m) {
  return m.size() == 0 ? 0.0 : m.cwiseAbs().maxCoeff();
}

// |got - expected|max / (1 + |expected|max); infinite if either holds a
// NaN or an infinity (an entry evaluate left unwritten among them).
template <class M>
double relative_error(const M& got, const M& expected) {
  if (!got.allFinite() || !expected.allFinite()) return std::numeric_limits<double>::infinity();
  return largest(got - expected) / (1.0 + largest(expected));
}

// The state's length scale, m: max(1 m, |x|max).
double length_scale(const State& s) { return std::max(1.0, max_abs(s.x)); }

bool all_finite(const ConstraintValues& v) {
  return v.value.allFinite() && v.rate.allFinite() && v.bias.allFinite() && v.jacobian.allFinite();
}

bool same_values(const ConstraintValues& a, const ConstraintValues& b) {
  return bit_equal(a.value, b.value) && bit_equal(a.rate, b.rate) && bit_equal(a.bias, b.bias) &&
         bit_equal(a.jacobian, b.jacobian);
}

// The first thing wrong with a pattern for `n` particles, or "".
std::string pattern_problem(const ConstraintPattern& pat, Index n) {
  if (pat.row_begin.empty() || pat.row_begin.front() != 0) {
    return "row_begin must start at 0";
  }
  if (pat.rows() < 1) return "no rows";
  if (pat.row_begin.back() != pat.entries()) {
    return fmt::format("row_begin ends at {}, expected the number of entries {}",
                       pat.row_begin.back(), pat.entries());
  }
  for (Index r = 0; r < pat.rows(); ++r) {
    if (pat.row_begin[r + 1] <= pat.row_begin[r]) {
      return fmt::format("row {} has no entries (row_begin must rise)", r);
    }
  }
  for (Index r = 0; r < pat.rows(); ++r) {
    for (Index e = pat.row_begin[r]; e < pat.row_begin[r + 1]; ++e) {
      const Index k = pat.particle[e];
      if (k < 0 || k >= n) {
        return fmt::format("row {} names particle {} (expected 0 to {})", r, k, n - 1);
      }
      for (Index e2 = pat.row_begin[r]; e2 < e; ++e2) {
        if (pat.particle[e2] == k) return fmt::format("row {} names particle {} twice", r, k);
      }
    }
  }
  return {};
}

bool same_pattern(const ConstraintPattern& a, const ConstraintPattern& b) {
  return a.row_begin == b.row_begin && a.particle == b.particle;
}

// What each group of constraint checks gets: the plugin, the object made
// with the sample parameters at the home state, its pattern, and the one
// random sequence the groups draw from in turn.
struct ConstraintCase {
  const PluginDescriptor& d;
  std::mt19937_64& rng;
  const State& home;
  const Constraint& c;
  const ConstraintPattern& pat;
  std::function<std::shared_ptr<Constraint>(const State&)> make;  // same parameters
};

// The home state and kRandomStates random ones (random velocities and times).
std::vector<State> test_states(ConstraintCase& c) {
  std::vector<State> states{c.home};
  for (int k = 0; k < kRandomStates; ++k) states.push_back(random_state(c.rng));
  return states;
}

// ---- the checks ----

CheckResult check_pattern(const ConstraintCase& c) {
  std::string problem = pattern_problem(c.pat, c.home.size());
  if (problem.empty()) {
    (void)values_at(c.c, c.pat, c.home);
    if (!same_pattern(c.pat, c.c.pattern())) problem = "pattern() changed after an evaluate()";
  }
  return result("constraint.pattern", problem.empty(), problem.empty() ? 0 : 1, 0,
                problem.empty()
                    ? fmt::format("{} rows, {} entries: row_begin rises from 0, every particle in "
                                  "0 .. {} and distinct within its row, the same on a second call",
                                  c.pat.rows(), c.pat.entries(), c.home.size() - 1)
                    : problem);
}

// Made at three states (the home state, two random ones) with the sample
// parameters, whose geometry defaults to the initial positions: C = 0 there.
CheckResult check_satisfied(ConstraintCase& c) {
  double worst = 0.0;
  for (int k = 0; k < 3; ++k) {
    const State s = k == 0 ? c.home : random_state(c.rng);
    std::shared_ptr<Constraint> obj;
    if (k > 0) obj = c.make(s);
    const Constraint& con = k == 0 ? c.c : *obj;
    const ConstraintPattern pat = k == 0 ? c.pat : con.pattern();
    if (!pattern_problem(pat, s.size()).empty()) {
      return result("constraint.satisfied_at_creation", false, 1, 0,
                    "malformed pattern for an object made at another state");
    }
    const Eigen::VectorXd value = value_at(con, pat, s);
    const double rel = value.allFinite() ? largest(value) / length_scale(s)
                                         : std::numeric_limits<double>::infinity();
    worst = std::max(worst, rel);
  }
  return result("constraint.satisfied_at_creation", worst <= kSatisfiedBound, worst,
                kSatisfiedBound,
                "|C|max / max(1 m, |x|max) at the state the object was made at (3 states, "
                "sample parameters, geometry from the initial positions)");
}

CheckResult check_jacobian(ConstraintCase& c) {
  double worst = 0.0;
  for (const State& s : test_states(c)) {
    const Eigen::MatrixXd j = dense_jacobian(c.pat, values_at(c.c, c.pat, s).jacobian, s.size());
    const Eigen::MatrixXd fd = jacobian_fd(c.c, c.pat, s);
    worst = std::max(worst, relative_error(j, fd));
  }
  return result("constraint.jacobian", worst <= kFirstBound, worst, kFirstBound,
                fmt::format("|J - dC/dx|max / (1 + |dC/dx|max), central differences (h = 1e-6 "
                            "max(1, |x|) m), on {} states; every particle, in the pattern or not",
                            kRandomStates + 1));
}

CheckResult check_rate(ConstraintCase& c) {
  double worst = 0.0;
  for (const State& at : test_states(c)) {
    const Eigen::VectorXd rate = values_at(c.c, c.pat, at).rate;
    State s = at;
    const double h = kFirstStep * std::max(1.0, std::abs(at.t));
    s.t = at.t + h;
    const Eigen::VectorXd up = value_at(c.c, c.pat, s);
    s.t = at.t - h;
    const Eigen::VectorXd down = value_at(c.c, c.pat, s);
    const Eigen::VectorXd fd = (up - down) / (2 * h);
    worst = std::max(worst, relative_error(rate, fd));
  }
  return result("constraint.rate", worst <= kFirstBound, worst, kFirstBound,
                fmt::format("|c_t - dC/dt|max / (1 + |dC/dt|max) at fixed x, central differences "
                            "(h = 1e-6 max(1, |t|) s), on {} states",
                            kRandomStates + 1));
}

// b = Cddot - J a: along x(t) = x + v t (a = 0), time running with it,
// Cddot is the second derivative of C(x + v s, t + s) in s at s = 0.
CheckResult check_bias(ConstraintCase& c) {
  double worst = 0.0;
  for (const State& at : test_states(c)) {
    const ConstraintValues v = values_at(c.c, c.pat, at);
    const double speed = max_abs(at.v), length = length_scale(at);
    const double h = kSecondStep * (speed > length ? length / speed : 1.0);
    State s = at;
    s.x = at.x + h * at.v;
    s.t = at.t + h;
    const Eigen::VectorXd up = value_at(c.c, c.pat, s);
    s.x = at.x - h * at.v;
    s.t = at.t - h;
    const Eigen::VectorXd down = value_at(c.c, c.pat, s);
    const Eigen::VectorXd fd = (up - 2.0 * v.value + down) / (h * h);
    worst = std::max(worst, relative_error(v.bias, fd));
  }
  return result("constraint.bias", worst <= kSecondBound, worst, kSecondBound,
                fmt::format("|b - d2C/dt2|max / (1 + |d2C/dt2|max) along x + v t (a = 0), central "
                            "second differences (h = 1e-4 s at |v| <= 1 m/s per m), on {} "
                            "states with random v",
                            kRandomStates + 1));
}

// Determinism, a read-only state, finite values.
void constraint_basic_checks(ConstraintCase& c, std::vector<CheckResult>& out) {
  guarded(out, "constraint.deterministic", [&] {
    const State s = random_state(c.rng);
    const auto other = c.make(c.home);
    const ConstraintPattern other_pat = other->pattern();
    bool same = same_pattern(c.pat, other_pat);
    for (const State* at : {&c.home, &s}) {
      if (!same) break;
      const ConstraintValues a = values_at(c.c, c.pat, *at), b = values_at(c.c, c.pat, *at);
      same = same_values(a, b) && same_values(a, values_at(*other, other_pat, *at));
    }
    return result("constraint.deterministic", same, same ? 0 : 1, 0,
                  "same state twice, and a second object, at 2 states: bit-identical C, c_t, b, J");
  });

  guarded(out, "constraint.read_only", [&] {
    const State before = random_state(c.rng);
    State s = before;
    (void)values_at(c.c, c.pat, s);
    const bool same = bit_equal(s.x, before.x) && bit_equal(s.v, before.v) &&
                      bit_equal(s.mass, before.mass) && s.fixed == before.fixed &&
                      s.radius == before.radius &&
                      std::memcmp(&s.t, &before.t, sizeof(double)) == 0;
    return result("constraint.read_only", same, same ? 0 : 1, 0,
                  "x, v, m, fixed, radius, t unchanged by evaluate");
  });

  guarded(out, "constraint.finite_on_degenerate", [&] {
    std::size_t bad = 0;
    std::string where;
    for (const auto& [label, s] : degenerate_states(c.rng)) {
      if (all_finite(values_at(c.c, c.pat, s))) continue;
      if (where.empty()) where = label;
      ++bad;
    }
    return result("constraint.finite_on_degenerate", bad == 0, static_cast<double>(bad), 0,
                  bad == 0 ? "coincident, at rest, far: every C, c_t, b, J written and finite"
                           : fmt::format("non-finite or unwritten values, first on: {}", where));
  });
}

void constraint_derivative_checks(ConstraintCase& c, std::vector<CheckResult>& out) {
  guarded(out, "constraint.satisfied_at_creation", [&] { return check_satisfied(c); });
  guarded(out, "constraint.jacobian", [&] { return check_jacobian(c); });
  guarded(out, "constraint.rate", [&] { return check_rate(c); });
  guarded(out, "constraint.bias", [&] { return check_bias(c); });
}

}  // namespace

void constraint_checks(const PluginDescriptor& d, const Options& o, std::vector<CheckResult>& out) {
  std::mt19937_64 rng(o.seed);
  const State home = random_state(rng);
  const Params params = sample_params(d, kParticles);
  auto make = [&](const State& at) {
    std::shared_ptr<Constraint> c(d.create_constraint(params, context_of(at)));
    if (!c) throw std::runtime_error("factory returned null");
    return c;
  };

  std::shared_ptr<Constraint> constraint;
  guarded(out, "construct.defaults", [&] {
    constraint = std::shared_ptr<Constraint>(d.create_constraint(params, context_of(home)));
    return result("construct.defaults", constraint != nullptr, constraint ? 1 : 0, 1,
                  constraint ? "created with defaults and sample values of required parameters "
                               "at a random state"
                             : "factory returned null");
  });
  if (!constraint) return;

  ConstraintPattern pat;
  bool well_formed = false;
  guarded(out, "constraint.pattern", [&] {
    pat = constraint->pattern();
    CheckResult r = check_pattern({d, rng, home, *constraint, pat, make});
    well_formed = r.verdict == Verdict::Pass;
    return r;
  });
  ConstraintCase c{d, rng, home, *constraint, pat, make};
  if (!well_formed) {
    // Evaluating through a malformed pattern could write out of bounds.
    for (const char* name : {"constraint.deterministic", "constraint.read_only",
                             "constraint.finite_on_degenerate", "constraint.satisfied_at_creation",
                             "constraint.jacobian", "constraint.rate", "constraint.bias"}) {
      out.push_back(skip(name, "the pattern is malformed (constraint.pattern)"));
    }
    return;
  }
  constraint_basic_checks(c, out);
  constraint_derivative_checks(c, out);
}

}  // namespace pdyn::conformance::detail
