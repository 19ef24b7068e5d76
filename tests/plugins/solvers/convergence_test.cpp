// Measured convergence orders of the shipped solvers on the harmonic
// oscillator of support/oscillator.hpp (a particle on a spring to a fixed
// anchor, against its closed form). A method of order p has a global error
// E(h) ~ C h^p at a fixed end time (t = 2 s here), so halving h divides E by
// 2^p. Two measurements, on two set-ups of the one oscillator:
//
//  - Convergence (euler, midpoint, rk4): a 1-D undamped oscillator with a
//    rest length (m = 1 kg, ks = 4 N/m, so w = 2 rad/s, period ~3.14 s;
//    r = 1 m, stretch 0.5 m, stretch rate 0.3 m/s), four step sizes h,
//    h/2, h/4, h/8 from h = 0.02 s (w h = 0.04 keeps every method in its
//    asymptotic range). Every successive pair's log2(E(h) / E(h/2)) must be
//    within 0.2 of the method's order, not only their average: a solver
//    that is order 4 on one pair and order 2 on another is broken. E is the
//    phase-space error sqrt(|dx|^2 + (|dv| / w)^2) (both in metres), so an
//    error in phase and one in amplitude both count and the norm cannot
//    vanish by accident at a zero of one component.
//  - ConvergenceOrder (symplectic_euler, verlet, rk45 at fixed steps,
//    implicit_euler): the 3-D oscillator on a zero-rest-length spring
//    (m = 0.5 kg, ks = 2 N/m, w0 = 2 rad/s, so t = 2 s is about 0.64
//    periods), four or five step counts, error max(|dx|, |dv| / w0). The
//    least-squares order must be within 0.3 of the declared order (the
//    descriptor's solver_traits), and the declared order must be the one
//    the method has.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "pdyn/host/runner.hpp"
#include "plugins/solvers/solver_support.hpp"

namespace pdyn {
namespace {

constexpr double kEnd = 2.0;  // s

using ErrorNorm = std::function<double(const test::Oscillator&, const System&)>;

// max(|dx|, |dv| / w0): the oscillator's own error().
double MaxError(const test::Oscillator& osc, const System& sys) { return osc.error(sys); }

// sqrt(|dx|^2 + (|dv| / w0)^2).
double PhaseSpaceError(const test::Oscillator& osc, const System& sys) {
  const double t = sys.time();
  return std::hypot((sys.positions().col(1) - osc.x(t)).norm(),
                    (sys.velocities().col(1) - osc.v(t)).norm() / osc.omega0());
}

// Errors at t = kEnd after `n` steps of kEnd / n, for each n of `steps`;
// prints them. The step sizes go to `hs` if given.
std::vector<double> Errors(const test::Oscillator& osc, const std::string& solver,
                           const std::vector<int>& steps, const ErrorNorm& norm,
                           std::vector<double>* hs = nullptr) {
  std::vector<double> errors;
  std::cout << solver << ":";
  for (const int n : steps) {
    const double h = kEnd / n;
    Scene scene =
        test::load_text(osc.scene(solver, "dt: " + test::Num(h) + ", steps: " + std::to_string(n)));
    const RunResult r = run_scene(scene);
    EXPECT_EQ(r.exit_code, 0) << r.message;
    EXPECT_EQ(r.steps_done, n) << solver;
    errors.push_back(norm(osc, *scene.system));
    if (hs) hs->push_back(h);
    std::cout << " h = " << h << ": " << errors.back() << ";";
  }
  std::cout << "\n";
  return errors;
}

// ---- Every successive pair: euler, midpoint, rk4 ------------------------------------------

test::Oscillator Undamped1D() {
  test::Oscillator o = test::Oscillator::Along(Vec3::UnitX(), 0.5, 0.3);
  o.mass = 1.0;
  o.ks = 4.0;
  o.rest = 1.0;
  return o;
}

class Convergence : public ::testing::TestWithParam<std::pair<const char*, double>> {};

TEST_P(Convergence, MeasuredOrderMatchesTheMethod) {
  const std::string solver = GetParam().first;
  const double expected = GetParam().second;
  const std::vector<int> steps = {100, 200, 400, 800};  // h = 0.02 s, halved three times
  const std::vector<double> errors =
      Errors(Undamped1D(), "{ type: " + solver + " }", steps, PhaseSpaceError);
  std::string orders;
  for (std::size_t i = 0; i + 1 < errors.size(); ++i) {
    const double order = std::log2(errors[i] / errors[i + 1]);
    std::ostringstream text;
    text << std::fixed << std::setprecision(4) << order;
    orders += (i ? ", " : "") + text.str();
    EXPECT_NEAR(order, expected, 0.2)
        << solver << ": errors " << errors[i] << " (h) and " << errors[i + 1] << " (h/2)";
  }
  std::cout << solver << " measured orders (dt " << kEnd / steps.front() << " -> "
            << kEnd / steps.back() << "): " << orders << "; errors " << errors.front() << " ... "
            << errors.back() << "\n";
  RecordProperty("measured_orders", orders);
}

INSTANTIATE_TEST_SUITE_P(Solvers, Convergence,
                         ::testing::Values(std::make_pair("euler", 1.0),
                                           std::make_pair("midpoint", 2.0),
                                           std::make_pair("rk4", 4.0)),
                         [](const auto& test_info) { return std::string(test_info.param.first); });

// ---- Least-squares order against the declared one ------------------------------------------

double MeasuredOrder(const test::Oscillator& osc, const std::string& solver,
                     const std::vector<int>& steps) {
  std::vector<double> hs;
  const std::vector<double> e = Errors(osc, solver, steps, MaxError, &hs);
  const double p = test::FittedOrder(hs, e);
  std::cout << solver << ": pairwise orders";
  for (std::size_t i = 1; i < e.size(); ++i) std::cout << " " << std::log2(e[i - 1] / e[i]);
  std::cout << "; fitted order " << p << "\n";
  return p;
}

int DeclaredOrder(const std::string& name) {
  const PluginRecord* r = test::shipped_plugins().find(PluginKind::Solver, name);
  EXPECT_NE(r, nullptr) << name;
  return r ? r->descriptor->solver_traits.order : -1;
}

TEST(ConvergenceOrder, SymplecticEulerIsFirstOrder) {
  EXPECT_EQ(DeclaredOrder("symplectic_euler"), 1);
  const double p =
      MeasuredOrder(test::Oscillator{}, "{ type: symplectic_euler }", {40, 80, 160, 320, 640});
  EXPECT_NEAR(p, 1.0, 0.3);
}

TEST(ConvergenceOrder, VerletIsSecondOrder) {
  EXPECT_EQ(DeclaredOrder("verlet"), 2);
  const double p = MeasuredOrder(test::Oscillator{}, "{ type: verlet }", {20, 40, 80, 160, 320});
  EXPECT_NEAR(p, 2.0, 0.3);
}

// With drag the force depends on v; the velocity predictor keeps verlet
// second order there too (with a1 taken at the half-step velocity it would
// fall to first order).
TEST(ConvergenceOrder, VerletStaysSecondOrderWithVelocityDependentForces) {
  test::Oscillator damped;
  damped.k = 0.3;
  const double p = MeasuredOrder(damped, "{ type: verlet }", {20, 40, 80, 160, 320});
  EXPECT_NEAR(p, 2.0, 0.3);
}

TEST(ConvergenceOrder, Rk45AtFixedStepIsFifthOrder) {
  EXPECT_EQ(DeclaredOrder("rk45"), 5);
  const double p =
      MeasuredOrder(test::Oscillator{}, "{ type: rk45, fixed_step: true }", {10, 20, 40, 80});
  EXPECT_NEAR(p, 5.0, 0.3);
}

TEST(ConvergenceOrder, ImplicitEulerIsFirstOrder) {
  EXPECT_EQ(DeclaredOrder("implicit_euler"), 1);
  test::Oscillator damped;
  damped.k = 0.3;  // exercises df/dv as well as df/dx
  const double p = MeasuredOrder(damped, "{ type: implicit_euler, cg_tolerance: 1.0e-12 }",
                                 {40, 80, 160, 320, 640});
  EXPECT_NEAR(p, 1.0, 0.3);
}

TEST(SolverTraits, SymplecticSolversSayTheyAre) {
  for (const auto& [name, symplectic] :
       std::vector<std::pair<std::string, bool>>{{"symplectic_euler", true},
                                                 {"verlet", true},
                                                 {"rk45", false},
                                                 {"implicit_euler", false}}) {
    const PluginRecord* r = test::shipped_plugins().find(PluginKind::Solver, name);
    ASSERT_NE(r, nullptr) << name;
    EXPECT_EQ(r->descriptor->solver_traits.symplectic, symplectic) << name;
  }
}

}  // namespace
}  // namespace pdyn
