// Helpers shared by the solver tests: the harmonic oscillator they integrate
// (support/oscillator.hpp, shared with the force tests) and a least-squares
// convergence order.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <string>
#include <vector>

#include "pdyn/force.hpp"
#include "support/oscillator.hpp"
#include "support/test_support.hpp"

namespace pdyn::test {

/// 27 Lennard-Jones atoms in a slightly sheared 3 x 3 x 3 cube under gravity
/// (forces on positions only), stepped by `solver` (a `solver:` entry),
/// `extra` inserted before `particles:` (colliders, a periodic box).
inline Scene LjCluster(const std::string& solver = "{ type: verlet }",
                       const std::string& extra = "") {
  std::string s =
      "simulation: { dt: 0.002, steps: 1, solver: " + solver + " }\n" + extra + "particles:\n";
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      for (int c = 0; c < 3; ++c)
        s += "  - { position: [" + std::to_string(1.12 * a) + ", " + std::to_string(1.12 * b) +
             ", " + std::to_string(1.12 * c + 0.05 * a) + "], mass: 1 }\n";
  s += "forces:\n  - { type: lennard_jones }\n  - { type: gravity, g: [0, 0, -9.81] }\n";
  return load_text(s);
}

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

/// Linear drag f = -0.02 v (N s/m) with no Jacobians: implicit_euler must
/// take its derivatives matrix-free (finite differences) while it takes the
/// other forces' analytically.
class OpaqueDrag final : public Force {
 public:
  void add_forces(const ParticleView& p, Eigen::Ref<Matrix3X> f) override { f -= 0.02 * p.v; }
};

}  // namespace pdyn::test
