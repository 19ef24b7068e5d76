// The constraint checks (pdyn/constraint.hpp): what every Constraint plugin
// must do (a well-formed pattern, deterministic, read-only on the state,
// finite when particles coincide and at the spots where a row's geometry is
// singular) and what its values claim, each against finite differences of C
// itself: the Jacobian dC/dx, the rate c_t = dC/dt at fixed positions, and
// the bias b = Cddot - J a along the straight motion x(t) = x + v t (a = 0);
// and that it is satisfied where it was created with the parameters a scene
// that gives only the required keys gets, as a constraint whose geometry is
// taken from the initial positions must be.
#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>

#include "checks.hpp"
#include "pdyn/constraint.hpp"
#include "pdyn/params.hpp"
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
// How far from a singular spot the "near" probes are, m: far enough that
// the squares of the distance (1e-20 m^2) are normal numbers, near enough
// that 1/distance (1e10 /m) dwarfs every other term.
constexpr double kNearSingular = 1e-10;

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

// A factory call: the object made with `params` at the state `at`.
using Maker = std::function<std::shared_ptr<Constraint>(const Params&, const State&)>;

// What each group of constraint checks gets: the plugin, the object made
// with the sample parameters at the home state, its pattern, the one random
// sequence the groups draw from in turn, and the two parameter sets
// (conformance.hpp: sample_params, default_params).
struct ConstraintCase {
  const PluginDescriptor& d;
  std::mt19937_64& rng;
  const State& home;
  const Constraint& c;
  const ConstraintPattern& pat;
  const Params& sample;
  const Params& defaults;
  Maker make_with;

  std::shared_ptr<Constraint> make(const State& at) const { return make_with(sample, at); }
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

// "length = 1, radius = 2": the parameters that took their defaults.
std::string defaults_used(const PluginDescriptor& d, const Params& p) {
  std::string list;
  for (const auto& spec : d.params) {
    if (!spec.fallback || !p.has(spec.name)) continue;
    const auto it = p.values().find(spec.name);
    list += (list.empty() ? "" : ", ") + spec.name + " = " + format_value(it->second);
  }
  return list;
}

// Made at three states (the home state, two random ones) with the default
// parameters: a geometry that the scene leaves out comes from the initial
// positions, so C = 0 there. The sample parameters would not do: a sample
// of an optional length is for the other checks, a scene leaving it out
// does not get it.
CheckResult check_satisfied(ConstraintCase& c) {
  double worst = 0.0;
  for (int k = 0; k < 3; ++k) {
    const State s = k == 0 ? c.home : random_state(c.rng);
    const std::shared_ptr<Constraint> con = c.make_with(c.defaults, s);
    const ConstraintPattern pat = con->pattern();
    if (!pattern_problem(pat, s.size()).empty()) {
      return result("constraint.satisfied_at_creation", false, 1, 0,
                    "malformed pattern for an object made at another state");
    }
    const Eigen::VectorXd value = value_at(*con, pat, s);
    const double rel = value.allFinite() ? largest(value) / length_scale(s)
                                         : std::numeric_limits<double>::infinity();
    worst = std::max(worst, rel);
  }
  const bool pass = worst <= kSatisfiedBound;
  std::string detail =
      "|C|max / max(1 m, |x|max) at the state the object was made at (3 states; default "
      "parameters: the required ones at their samples, the others at their defaults or left "
      "out, so that a geometry left out comes from the initial positions)";
  if (!pass) {
    const std::string used = defaults_used(c.d, c.defaults);
    detail = fmt::format(
        "C != 0 where the object was made, with the default parameters{}: a geometry that a "
        "scene leaves out must come from the initial positions (declare it with "
        "param::optional, no default; docs/constraints.md)",
        used.empty() ? "" : " (" + used + ")");
  }
  return result("constraint.satisfied_at_creation", pass, worst, kSatisfiedBound, detail);
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

// ---- near-singular states ----
//
// A row's geometry is singular where a direction it divides by vanishes: a
// bead on the axis of its wire or cylinder (1/rho), a particle at a
// sphere's centre or at the origin (1/r), two particles of a row on one
// point. A plugin must stay finite there, or refuse with a message: the kit
// cannot know a plugin's axes, so it puts the particles on every point and
// line the coordinate frame and the parameters name.

// A point or a direction, with how the report names it.
struct Landmark {
  std::string name;
  Vec3 at;
};

bool known(const std::vector<Landmark>& list, const Vec3& p) {
  return std::any_of(list.begin(), list.end(), [&](const Landmark& l) { return l.at == p; });
}

// The points (the origin, every Vector parameter's value, every VectorList's
// first) and the directions (x, y, z, every nonzero Vector parameter's) of
// both parameter sets.
void landmarks(const Params& params, std::vector<Landmark>& points,
               std::vector<Landmark>& directions) {
  for (const auto& [name, value] : params.values()) {
    const Vec3* v = std::get_if<Vec3>(&value);
    const auto* list = std::get_if<std::vector<Vec3>>(&value);
    if (list && !list->empty()) v = &list->front();
    if (!v || !v->allFinite()) continue;
    if (!known(points, *v)) points.push_back({fmt::format("`{}` {}", name, format_value(*v)), *v});
    if (v->norm() == 0.0) continue;
    const Vec3 u = v->normalized();
    if (!known(directions, u) && !known(directions, -u)) {
      directions.push_back({fmt::format("`{}`", name), u});
    }
  }
}

// The labelled states: every particle on each point; on each line through
// each point along each direction (at distinct distances, 0.2 .. 1 m either
// side); every particle within 1e-10 m of particle 0; and each of these
// again with every particle moved 1e-10 m off in a random direction.
// Velocities and time are random.
std::vector<std::pair<std::string, State>> near_singular_states(std::mt19937_64& rng,
                                                                const Params& a, const Params& b) {
  std::vector<Landmark> points{{"the origin", Vec3::Zero()}};
  std::vector<Landmark> directions{
      {"x", Vec3::UnitX()}, {"y", Vec3::UnitY()}, {"z", Vec3::UnitZ()}};
  landmarks(a, points, directions);
  landmarks(b, points, directions);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const State base = random_state(rng);
  std::vector<std::pair<std::string, State>> exact;
  for (const Landmark& p : points) {
    State s = base;
    s.x.colwise() = p.at;
    exact.emplace_back("every particle at " + p.name, s);
    for (const Landmark& d : directions) {
      for (Index i = 0; i < s.size(); ++i) {
        const double along = (i % 2 == 0 ? 1.0 : -1.0) * (0.2 + 0.8 * (i + 0.5 * (1.0 + u(rng))) /
                                                                    static_cast<double>(s.size()));
        s.x.col(i) = p.at + along * d.at;
      }
      exact.emplace_back(fmt::format("on the line through {} along {}", p.name, d.name), s);
    }
  }
  State coincident = base;
  coincident.x.colwise() = base.x.col(0);
  exact.emplace_back("every particle at particle 0's point", coincident);
  std::vector<std::pair<std::string, State>> out = exact;
  for (auto [label, s] : exact) {
    for (Index i = 0; i < s.size(); ++i) {
      const Vec3 off(u(rng), u(rng), u(rng));
      s.x.col(i) += kNearSingular * off.normalized();
    }
    out.emplace_back(fmt::format("within {:g} m of: {}", kNearSingular, label), s);
  }
  return out;
}

// "": `con` at `s` gives finite C, c_t, b and J, or refuses with a message
// (counted in `refusals`); else what went wrong.
std::string finite_or_refused(const Constraint& con, const ConstraintPattern& pat, const State& s,
                              std::size_t& refusals) {
  try {
    if (all_finite(values_at(con, pat, s))) return {};
    return "non-finite or unwritten values";
  } catch (const std::exception& e) {
    if (std::string(e.what()).empty()) return "an exception without a message";
    ++refusals;
    return {};
  }
}

// Each state with the object made at the home state, and with objects made
// at that state (sample and default parameters): a geometry taken from a
// particle on an axis (a radius 0) is made there. Making may be refused with
// a message too.
CheckResult check_near_singular(ConstraintCase& c) {
  const auto states = near_singular_states(c.rng, c.sample, c.defaults);
  std::size_t bad = 0, refusals = 0;
  std::string first;
  auto note = [&](const std::string& problem, const std::string& where) {
    if (problem.empty()) return;
    if (first.empty()) first = fmt::format("{}, on: {}", problem, where);
    ++bad;
  };
  for (const auto& [label, s] : states) {
    note(finite_or_refused(c.c, c.pat, s, refusals), label + " (made at a random state)");
    for (const Params* params : {&c.sample, &c.defaults}) {
      std::shared_ptr<Constraint> made;
      try {
        made = c.make_with(*params, s);
      } catch (const std::exception& e) {
        note(std::string(e.what()).empty() ? "refused without a message" : "", label);
        refusals += std::string(e.what()).empty() ? 0 : 1;
        continue;
      }
      const ConstraintPattern pat = made->pattern();
      const std::string problem = pattern_problem(pat, s.size());
      note(problem.empty() ? finite_or_refused(*made, pat, s, refusals) : problem,
           label + " (made there)");
    }
  }
  return result(
      "constraint.finite_near_singular", bad == 0, static_cast<double>(bad), 0,
      bad == 0 ? fmt::format("{} states: every particle at the origin and at each point the "
                             "parameters name, on each line through them along x, y, z and "
                             "each direction the parameters name, on one random point; each "
                             "again within {:g} m; made elsewhere and made there: every C, c_t, "
                             "b, J finite or refused with a message ({} refusals)",
                             states.size(), kNearSingular, refusals)
               : first);
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
                      std::bit_cast<std::uint64_t>(s.t) == std::bit_cast<std::uint64_t>(before.t);
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
                  bad == 0 ? "every particle on one random point (random v, and at rest), every "
                             "particle at rest, all moved 1e6 m out: every C, c_t, b, J "
                             "written and finite"
                           : fmt::format("non-finite or unwritten values, first on: {}", where));
  });

  guarded(out, "constraint.finite_near_singular", [&] { return check_near_singular(c); });
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
  Params defaults = default_params(d, kParticles);
  Maker make = [&](const Params& with, const State& at) {
    std::shared_ptr<Constraint> c(d.create_constraint(with, context_of(at)));
    if (!c) throw std::runtime_error("factory returned null");
    return c;
  };
  // A plugin that needs one of two optional lists (distance: pairs or
  // triples) refuses the bare defaults by naming an optional parameter
  // that declares a sample and that default_params left out: its samples
  // are then its defaults. Any other refusal keeps the bare defaults, and
  // the checks that build with them report it.
  try {
    make(defaults, home);
  } catch (const ParamError& e) {
    const auto spec = std::find_if(d.params.begin(), d.params.end(),
                                   [&](const ParamSpec& s) { return s.name == e.param(); });
    if (spec != d.params.end() && !spec->required && spec->sample && !defaults.has(e.param())) {
      defaults = params;
    }
  }

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
    CheckResult r = check_pattern({d, rng, home, *constraint, pat, params, defaults, make});
    well_formed = r.verdict == Verdict::Pass;
    return r;
  });
  ConstraintCase c{d, rng, home, *constraint, pat, params, defaults, make};
  if (!well_formed) {
    // Evaluating through a malformed pattern could write out of bounds.
    for (const char* name :
         {"constraint.deterministic", "constraint.read_only", "constraint.finite_on_degenerate",
          "constraint.finite_near_singular", "constraint.satisfied_at_creation",
          "constraint.jacobian", "constraint.rate", "constraint.bias"}) {
      out.push_back(skip(name, "the pattern is malformed (constraint.pattern)"));
    }
    return;
  }
  constraint_basic_checks(c, out);
  constraint_derivative_checks(c, out);
}

}  // namespace pdyn::conformance::detail
