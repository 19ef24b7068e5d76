// Helpers for the collider tests: a seeded random cloud of throws, and the
// speed ratio of a first impact.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <random>
#include <vector>

#include "support/physics_support.hpp"
#include "support/test_support.hpp"

namespace pdyn::test {

/// Uniform in [0, 1) from the top 53 bits: the same numbers on every
/// standard library (std::uniform_real_distribution is not).
inline double Uniform(std::mt19937_64& g) { return static_cast<double>(g() >> 11) * 0x1.0p-53; }

/// A uniformly random unit vector.
inline Vec3 RandomDirection(std::mt19937_64& g) {
  Vec3 u;
  do {
    for (int a = 0; a < 3; ++a) u[a] = 2.0 * Uniform(g) - 1.0;
  } while (u.squaredNorm() > 1.0 || u.squaredNorm() < 1e-6);
  return u.normalized();
}

/// Scene text: `n` particles of 0.01 kg, gravity g, and the collider line.
inline std::string ThrowScene(int n, double dt, double g, const std::string& collider) {
  return "simulation: { dt: " + Num(dt) +
         ", steps: 1, solver: { type: rk4 } }\n"
         "particles:\n"
         "  - cloud: { n: " +
         std::to_string(n) +
         ", box: { min: [-1, -1, -1], max: [1, 1, 1] }, mass: 0.01, seed: 1 }\n"
         "forces:\n"
         "  - { type: gravity, g: [0, 0, " +
         Num(-g) +
         "] }\n"
         "colliders:\n"
         "  - " +
         collider + "\n";
}

/// Runs `steps` steps of `h` and returns the worst penetration found at the
/// end of any step, max over particles and steps of -distance(x) (m; <= 0
/// when no particle ever ended inside), and counts in `contacts` the
/// particles that ended some step within 1 mm of the surface (so a test
/// can check that the throws reached it at all).
inline double WorstPenetration(Scene& scene, int steps, double h,
                               const std::function<double(const Vec3&)>& distance, int& contacts) {
  double worst = -1e300;
  System& sys = *scene.system;
  std::vector<bool> touched(static_cast<std::size_t>(sys.size()), false);
  for (int k = 1; k <= steps; ++k) {
    TakeStep(scene, k, h);
    for (Index i = 0; i < sys.size(); ++i) {
      const double d = distance(sys.positions().col(i));
      worst = std::max(worst, -d);
      if (std::abs(d) < 1e-3) touched[static_cast<std::size_t>(i)] = true;
    }
  }
  contacts = static_cast<int>(std::count(touched.begin(), touched.end(), true));
  return worst;
}

/// Steps a single particle until its velocity changes direction (its first
/// impact) and returns |v after| / |v before|, and the position and
/// velocities at the impact.
struct Impact {
  double ratio = -1.0;
  Vec3 x, v_in, v_out;
};
inline Impact FirstImpact(Scene& scene, double h, int max_steps) {
  System& sys = *scene.system;
  Impact r;
  for (int k = 1; k <= max_steps; ++k) {
    const Vec3 before = sys.velocities().col(0);
    TakeStep(scene, k, h);
    const Vec3 after = sys.velocities().col(0);
    if ((after - before).norm() > 1e-9) {
      r.ratio = after.norm() / before.norm();
      r.x = sys.positions().col(0);
      r.v_in = before;
      r.v_out = after;
      return r;
    }
  }
  return r;
}

/// A scene of one 0.1 kg particle at `x` (m) moving at `v` (m/s), stepped
/// with rk4 at dt = 1 ms, and the collider given as YAML flow text.
inline Scene OneParticle(const Vec3& x, const Vec3& v, const std::string& collider) {
  return load_text(
      "simulation: { dt: 0.001, steps: 1, solver: { type: rk4 } }\n"
      "particles:\n"
      "  - { position: " +
      Vec(x) + ", velocity: " + Vec(v) +
      ", mass: 0.1 }\n"
      "colliders:\n"
      "  - " +
      collider + "\n");
}

}  // namespace pdyn::test
