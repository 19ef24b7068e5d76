// The harmonic oscillator the tests integrate, written once: a particle on a
// spring to a fixed anchor (optionally damped by the spring and by linear
// drag), its closed form and the scene that builds it.
//
// Particle 0 is the anchor, fixed at `anchor`; particle 1 (mass m) hangs on
// a spring (ks, kd, rest length r) to it, under drag k if k > 0. The
// equilibrium is p = anchor + r e (e = axis, normalised); particle 1 starts
// at p + x0 with velocity v0.
//  - With r = 0 and kd = 0 the force is -ks (x - anchor) - k v, exactly
//    linear in every direction: x0 and v0 may point anywhere.
//  - With r > 0 or kd > 0, x0 and v0 must lie along e: the particle then
//    moves on the spring's axis and its stretch u obeys the same 1-D
//    equation (the amplitude must stay below r, where the spring's
//    direction, and this reduction, would break down).
// Each component of the displacement d = x - p is the damped oscillator
//   m d'' + (k + kd) d' + ks d = 0,
//   d(t) = e^{-g t} (A cos(w t) + B sin(w t)),  g = (k + kd) / 2m,
//   w = sqrt(ks/m - g^2),  A = d0,  B = (d0' + g d0) / w
// (underdamped or undamped).
//
// conformance/ integrates the same closed form (w = 1, a code-built anchor
// force) in its solver.convergence_order check.
#pragma once

#include <algorithm>
#include <cmath>
#include <string>

#include "pdyn/system.hpp"
#include "support/physics_support.hpp"

namespace pdyn::test {

struct Oscillator {
  double mass = 0.5;           // kg
  double ks = 2.0;             // N/m: w0 = 2 rad/s
  double kd = 0.0;             // N s/m, the spring's damping
  double k = 0.0;              // kg/s, linear drag
  double rest = 0.0;           // m, the spring's rest length
  Vec3 anchor = Vec3::Zero();  // m
  Vec3 axis = Vec3::UnitX();   // the spring's direction at rest (used if rest > 0)
  Vec3 x0{0.3, -0.2, 0.5};     // m, displacement from the equilibrium
  Vec3 v0{0.4, 0.7, -0.1};     // m/s

  /// A 1-D oscillator along `along` (normalised): stretch u0, rate u0_dot.
  static Oscillator Along(const Vec3& along, double u0, double u0_dot) {
    Oscillator o;
    o.axis = along.normalized();
    o.x0 = u0 * o.axis;
    o.v0 = u0_dot * o.axis;
    return o;
  }

  double gamma() const { return (k + kd) / (2.0 * mass); }
  double omega() const { return std::sqrt(ks / mass - gamma() * gamma()); }
  /// The undamped angular frequency sqrt(ks/m), rad/s.
  double omega0() const { return std::sqrt(ks / mass); }
  /// Where the particle rests: anchor + r e.
  Vec3 equilibrium() const { return anchor + rest * axis.normalized(); }

  /// Displacement from the equilibrium and its rate at time t.
  Vec3 d(double t) const {
    const double g = gamma(), w = omega();
    const Vec3 b = (v0 + g * x0) / w;
    return std::exp(-g * t) * (x0 * std::cos(w * t) + b * std::sin(w * t));
  }
  Vec3 v(double t) const {
    const double g = gamma(), w = omega();
    const Vec3 b = (v0 + g * x0) / w;
    return std::exp(-g * t) *
           ((b * w - g * x0) * std::cos(w * t) - (x0 * w + g * b) * std::sin(w * t));
  }
  /// Position of particle 1 at time t, m.
  Vec3 x(double t) const { return equilibrium() + d(t); }
  /// Mechanical energy m |v|^2 / 2 + ks |d|^2 / 2 at time t, J (the
  /// spring's potential, since |d| is its stretch).
  double energy(double t) const {
    return 0.5 * mass * v(t).squaredNorm() + 0.5 * ks * d(t).squaredNorm();
  }

  /// The scene: particle 0 the fixed anchor, particle 1 the oscillator.
  /// `solver` is the YAML of the solver mapping, `timing` the rest of the
  /// simulation section (e.g. "dt: 0.01, steps: 100").
  std::string scene(const std::string& solver, const std::string& timing) const {
    std::string s = "simulation: { " + timing + ", solver: " + solver + " }\n" +
                    "particles:\n"
                    "  - { position: " +
                    Vec(anchor) +
                    ", mass: 1, fixed: true }\n"
                    "  - { position: " +
                    Vec(equilibrium() + x0) + ", velocity: " + Vec(v0) + ", mass: " + Num(mass) +
                    " }\n" +
                    "forces:\n"
                    "  - { type: spring, pairs: [[1, 0]], ks: " +
                    Num(ks) + (kd > 0.0 ? ", kd: " + Num(kd) : std::string()) + ", rest: [" +
                    Num(rest) + "] }\n";
    if (k > 0.0) s += "  - { type: drag, k: " + Num(k) + " }\n";
    return s;
  }

  /// Phase-space error of particle 1 of `sys` against the closed form at
  /// the system's time: max(|x - x(t)|, |v - v(t)| / w0), m.
  double error(const System& sys) const {
    const double t = sys.time();
    return std::max((sys.positions().col(1) - x(t)).lpNorm<Eigen::Infinity>(),
                    (sys.velocities().col(1) - v(t)).lpNorm<Eigen::Infinity>() / omega0());
  }
};

}  // namespace pdyn::test
