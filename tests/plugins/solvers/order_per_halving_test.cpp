// Measured order of accuracy of each shipped solver on a harmonic oscillator.
//
// A particle of mass m on an undamped spring (ks, rest r) to a fixed
// particle, displaced along x: its stretch u obeys u'' = -w^2 u, w^2 = ks/m,
// so u(t) = u0 cos(w t) + (u0' / w) sin(w t). A method of order p has a
// global error E(h) ~ C h^p at a fixed end time, so halving h divides E by
// 2^p and log2(E(h) / E(h/2)) measures p. We run four step sizes (h, h/2,
// h/4, h/8) and check every successive pair, not only their average: a
// solver that is order 4 on one pair and order 2 on another is broken.
#include <gtest/gtest.h>

#include <cmath>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "support/physics_support.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

constexpr double kMass = 1.0;       // kg
constexpr double kKs = 4.0;         // N/m: w = 2 rad/s, period ~3.14 s
constexpr double kRest = 1.0;       // m
constexpr double kU0 = 0.5;         // m
constexpr double kUDot0 = 0.3;      // m/s
constexpr double kEndTime = 2.0;    // s
constexpr double kCoarseDt = 0.02;  // s; wh = 0.04 keeps every method in its asymptotic range

// Global error at kEndTime with step h, in phase space: sqrt(du^2 + (du'/w)^2)
// (both in metres), so an error in phase and one in amplitude both count and
// the norm cannot vanish by accident at a zero of one component.
double ErrorAtEnd(const std::string& solver, double h) {
  const int steps = static_cast<int>(std::lround(kEndTime / h));
  Scene scene =
      test::load_text("simulation: { dt: " + test::Num(h) + ", steps: " + std::to_string(steps) +
                      ", solver: { type: " + solver +
                      " } }\n"
                      "particles:\n"
                      "  - { position: [0, 0, 0], mass: 1, fixed: true }\n"
                      "  - { position: [" +
                      test::Num(kRest + kU0) + ", 0, 0], velocity: [" + test::Num(kUDot0) +
                      ", 0, 0], mass: " + test::Num(kMass) +
                      " }\n"
                      "forces:\n"
                      "  - { type: spring, pairs: [[0, 1]], ks: " +
                      test::Num(kKs) + ", rest: [" + test::Num(kRest) + "] }\n");
  for (int k = 1; k <= steps; ++k) test::TakeStep(scene, k, h);
  const double w = std::sqrt(kKs / kMass);
  const double t = steps * h;
  const double u = kU0 * std::cos(w * t) + kUDot0 / w * std::sin(w * t);
  const double u_dot = -kU0 * w * std::sin(w * t) + kUDot0 * std::cos(w * t);
  const System& sys = *scene.system;
  const double du = sys.positions()(0, 1) - (kRest + u);
  const double dv = sys.velocities()(0, 1) - u_dot;
  return std::hypot(du, dv / w);
}

class Convergence : public ::testing::TestWithParam<std::pair<const char*, double>> {};

TEST_P(Convergence, MeasuredOrderMatchesTheMethod) {
  const std::string solver = GetParam().first;
  const double expected = GetParam().second;
  std::vector<double> errors;
  for (int halvings = 0; halvings <= 3; ++halvings) {
    errors.push_back(ErrorAtEnd(solver, kCoarseDt / std::pow(2.0, halvings)));
  }
  std::string orders;
  for (std::size_t i = 0; i + 1 < errors.size(); ++i) {
    const double order = std::log2(errors[i] / errors[i + 1]);
    std::ostringstream text;
    text << std::fixed << std::setprecision(4) << order;
    orders += (i ? ", " : "") + text.str();
    EXPECT_NEAR(order, expected, 0.2)
        << solver << ": errors " << errors[i] << " (h) and " << errors[i + 1] << " (h/2)";
  }
  std::cout << solver << " measured orders (dt " << kCoarseDt << " -> " << kCoarseDt / 8
            << "): " << orders << "; errors " << errors[0] << " ... " << errors[3] << "\n";
  RecordProperty("measured_orders", orders);
}

INSTANTIATE_TEST_SUITE_P(Solvers, Convergence,
                         ::testing::Values(std::make_pair("euler", 1.0),
                                           std::make_pair("midpoint", 2.0),
                                           std::make_pair("rk4", 4.0)),
                         [](const auto& test_info) { return std::string(test_info.param.first); });

}  // namespace
}  // namespace pdyn
