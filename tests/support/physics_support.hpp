// Helpers shared by the tests that integrate physics (plugins/, gallery/):
// exact number formatting for inline YAML scenes and Witkin's simulation
// loop (step, set time, collide).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include "pdyn/force.hpp"
#include "pdyn/host/assembly.hpp"
#include "pdyn/host/scene.hpp"
#include "pdyn/host/stepper.hpp"
#include "pdyn/solver.hpp"
#include "pdyn/system.hpp"
#include "support/test_support.hpp"

namespace pdyn::test {

/// A force that adds nothing and claims the default dependence (velocity and
/// time): a force object whose presence alone is under test.
class Nothing final : public Force {
 public:
  void add_forces(const ParticleView&, Eigen::Ref<Matrix3X>) override {}
};

/// `x` with 17 significant digits, so the scene loader reads back exactly
/// the double the test compares against.
inline std::string Num(double x) {
  std::ostringstream s;
  s << std::setprecision(17) << x;
  return s.str();
}

/// "[x, y, z]" with 17 significant digits.
inline std::string Vec(const Vec3& v) {
  return "[" + Num(v.x()) + ", " + Num(v.y()) + ", " + Num(v.z()) + "]";
}

/// The deepest overlap of equal spheres of `diameter` (m) centred on the
/// system's particles: the largest diameter - |x_i - x_j| over all pairs, m
/// (negative when none touch). O(N^2), for checks.
inline double DeepestOverlap(const System& sys, double diameter) {
  double deepest = -std::numeric_limits<double>::infinity();
  for (Index i = 0; i < sys.size(); ++i) {
    for (Index j = i + 1; j < sys.size(); ++j) {
      deepest =
          std::max(deepest, diameter - (sys.positions().col(i) - sys.positions().col(j)).norm());
    }
  }
  return deepest;
}

/// Step k (1-based) of length h, as the kernel's runner takes it: the solver
/// step, the time set to k h (computed, not accumulated), then the
/// colliders' response and the wrap into a periodic box. Also checks the Solver contract that a
/// step advances the system's time by h; a breach throws, which fails the test once instead of once
/// per step.
inline void TakeStep(Scene& scene, std::int64_t k, double h) {
  const double t0 = scene.system->time();
  scene.solver->step(*scene.system, h);
  if (std::abs(scene.system->time() - (t0 + h)) > 1e-12 * std::max(1.0, std::abs(t0))) {
    throw std::logic_error(scene.solver_name + " step " + std::to_string(k) +
                           " from t = " + Num(t0) + " with h = " + Num(h) +
                           " ended at t = " + Num(scene.system->time()) + " (expected t + h)");
  }
  scene.system->set_time(static_cast<double>(k) * h);
  SystemAssembly(*scene.system).respond_to_collisions(h);
  SystemAssembly(*scene.system).wrap_positions();  // as the Stepper does after a good step
}

/// LAMMPS's Lennard-Jones liquid (tests/scenes/thermo: 256 atoms, fcc at
/// density 0.8442, T* = 1.44, in its periodic box) stepped by `solver` (a
/// `solver:` entry), under lennard_jones (epsilon = sigma = 1, cutoff 2.5,
/// shifted to 0 there if `shift`) and the force entries `more` ("  - {...}\n").
inline Scene LjLiquid(const std::string& solver, const std::string& more = "", bool shift = false) {
  const std::string data = source_path("tests/scenes/thermo/thermo_start.data").string();
  return load_text("simulation: { dt: 0.005, steps: 1, solver: " + solver +
                   ", box: { file: " + data + " } }\nparticles:\n  - file: " + data +
                   "\nforces:\n  - { type: lennard_jones, epsilon: 1, sigma: 1, cutoff: 2.5, "
                   "skin: 0.3, shift: " +
                   (shift ? "true" : "false") + " }\n" + more);
}

/// Steps `scene` through a Stepper, as pdyn run does (the forces told each
/// step's start and length, pdyn/step_aware.hpp; the wrap; the rollback),
/// `steps` steps of scene.dt, calling each(k) after step k.
template <class Each>
void StepThrough(Scene& scene, std::int64_t steps, Each&& each) {
  Stepper stepper(*scene.system, *scene.solver, scene.solver_label);
  for (std::int64_t k = 1; k <= steps; ++k) {
    ASSERT_TRUE(stepper.step_to(static_cast<double>(k) * scene.dt)) << stepper.fault().what;
    each(k);
  }
}

}  // namespace pdyn::test
