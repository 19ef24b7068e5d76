// Helpers shared by the solver tests: the harmonic oscillator they integrate
// (a particle on a zero-rest-length spring to a fixed anchor at the origin,
// so f = -ks x - k v is exactly linear in every direction) and its closed
// form, and a least-squares convergence order.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "support/physics_support.hpp"
#include "support/test_support.hpp"

namespace pdyn::test {

/// m x'' + k x' + ks x = 0 in 3-D, from x0, v0 at t = 0 (underdamped or
/// undamped). Each component is the damped oscillator
///   u(t) = e^{-g t} (A cos(w t) + B sin(w t)),  g = k / 2m,
///   w = sqrt(ks/m - g^2),  A = u0,  B = (u0' + g u0) / w.
struct Oscillator {
  double mass = 0.5;        // kg
  double ks = 2.0;          // N/m: w0 = 2 rad/s
  double k = 0.0;           // kg/s, linear drag
  Vec3 x0{0.3, -0.2, 0.5};  // m
  Vec3 v0{0.4, 0.7, -0.1};  // m/s

  double gamma() const { return k / (2.0 * mass); }
  double omega() const { return std::sqrt(ks / mass - gamma() * gamma()); }
  Vec3 x(double t) const {
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
  /// Mechanical energy m v^2/2 + ks x^2/2, J.
  double energy(const Vec3& x, const Vec3& v) const {
    return 0.5 * mass * v.squaredNorm() + 0.5 * ks * x.squaredNorm();
  }

  /// The scene: particle 0 the fixed anchor, particle 1 the oscillator.
  /// `solver` is the YAML of the solver mapping, `timing` the rest of the
  /// simulation section (e.g. "dt: 0.01, steps: 100").
  std::string scene(const std::string& solver, const std::string& timing) const {
    std::string s = "simulation: { " + timing + ", solver: " + solver + " }\n" +
                    "particles:\n"
                    "  - { position: [0, 0, 0], mass: 1, fixed: true }\n"
                    "  - { position: " +
                    Vec(x0) + ", velocity: " + Vec(v0) + ", mass: " + Num(mass) + " }\n" +
                    "forces:\n"
                    "  - { type: spring, pairs: [[1, 0]], ks: " +
                    Num(ks) + ", rest: [0] }\n";
    if (k > 0.0) s += "  - { type: drag, k: " + Num(k) + " }\n";
    return s;
  }

  /// Phase-space error of particle 1 of `sys` against the closed form at
  /// the system's time: max(|x - x(t)|, |v - v(t)| / w0), m.
  double error(const System& sys) const {
    const double t = sys.time();
    const double w0 = std::sqrt(ks / mass);
    return std::max((sys.positions().col(1) - x(t)).lpNorm<Eigen::Infinity>(),
                    (sys.velocities().col(1) - v(t)).lpNorm<Eigen::Infinity>() / w0);
  }
};

/// Slope of log(error) against log(h), least squares.
inline double FittedOrder(const std::vector<double>& h, const std::vector<double>& error) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  const double n = static_cast<double>(h.size());
  for (std::size_t i = 0; i < h.size(); ++i) {
    const double lx = std::log(h[i]), ly = std::log(error[i]);
    sx += lx;
    sy += ly;
    sxx += lx * lx;
    sxy += lx * ly;
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

}  // namespace pdyn::test
