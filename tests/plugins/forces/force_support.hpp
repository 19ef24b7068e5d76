// Helpers shared by the force plugins' tests: random particle clouds as
// inline scenes, one force object's forces alone, -grad U by central
// differences, and the net force and torque of a force field.
#pragma once

#include <Eigen/Geometry>
#include <random>
#include <string>
#include <vector>

#include "pdyn/system.hpp"
#include "support/physics_support.hpp"
#include "support/test_support.hpp"

namespace pdyn::test {

/// Collects a force's Jacobian blocks (Force::add_jacobians) into dense
/// 3N x 3N matrices df/dx (N/m) and df/dv (N s/m), for comparison with
/// finite differences.
class DenseSink final : public JacobianSink {
 public:
  explicit DenseSink(Index n)
      : dfdx(Eigen::MatrixXd::Zero(3 * n, 3 * n)), dfdv(Eigen::MatrixXd::Zero(3 * n, 3 * n)) {}
  void add_dfdx(Index i, Index j, const Eigen::Matrix3d& b) override {
    dfdx.block<3, 3>(3 * i, 3 * j) += b;
  }
  void add_dfdv(Index i, Index j, const Eigen::Matrix3d& b) override {
    dfdv.block<3, 3>(3 * i, 3 * j) += b;
  }
  Eigen::MatrixXd dfdx, dfdv;
};

/// A reproducible random cloud of particles (positions in [-1, 1]^3 m,
/// velocities in [-2, 2]^3 m/s, masses in [0.5, 2] kg) as a scene's
/// `simulation` and `particles` sections.
struct Cloud {
  explicit Cloud(int n, unsigned seed) : rng(seed) {
    std::uniform_real_distribution<double> pos(-1.0, 1.0), vel(-2.0, 2.0), mass(0.5, 2.0);
    for (int i = 0; i < n; ++i) {
      x.emplace_back(pos(rng), pos(rng), pos(rng));
      v.emplace_back(vel(rng), vel(rng), vel(rng));
      m.push_back(mass(rng));
    }
  }
  std::string Yaml() const {
    std::string s = "simulation: { dt: 0.001, steps: 1 }\nparticles:\n";
    for (std::size_t i = 0; i < x.size(); ++i) {
      s += "  - { position: " + Vec(x[i]) + ", velocity: " + Vec(v[i]) + ", mass: " + Num(m[i]) +
           " }\n";
    }
    return s;
  }
  /// `count` random triples of distinct particles, as "[[i, j, k], ...]".
  std::string Triples(int count) {
    std::uniform_int_distribution<int> pick(0, static_cast<int>(x.size()) - 1);
    std::string s = "[";
    for (int t = 0; t < count; ++t) {
      int i = pick(rng), j = pick(rng), k = pick(rng);
      while (j == i) j = pick(rng);
      while (k == i || k == j) k = pick(rng);
      s += (t ? ", [" : "[") + std::to_string(i) + ", " + std::to_string(j) + ", " +
           std::to_string(k) + "]";
    }
    return s + "]";
  }
  std::mt19937 rng;
  std::vector<Vec3> x, v;
  std::vector<double> m;
};

/// The forces (3 x N) that force object `index` of `sys` alone adds to zero.
inline Matrix3X ForcesOf(const System& sys, std::size_t index) {
  Matrix3X f = Matrix3X::Zero(3, sys.size());
  sys.force_objects().at(index).force->add_forces(sys.view(), f);
  return f;
}

/// -grad U of force object `index` by central differences of its reported
/// potential energy, step `h` (m) in every coordinate of every particle.
inline Matrix3X MinusGradient(System& sys, std::size_t index, double h) {
  const Force& force = *sys.force_objects().at(index).force;
  Matrix3X g(3, sys.size());
  for (Index i = 0; i < sys.size(); ++i) {
    for (int c = 0; c < 3; ++c) {
      const double saved = sys.positions()(c, i);
      sys.positions()(c, i) = saved + h;
      const double up = force.potential_energy(sys.view()).value();
      sys.positions()(c, i) = saved - h;
      const double down = force.potential_energy(sys.view()).value();
      sys.positions()(c, i) = saved;
      g(c, i) = -(up - down) / (2.0 * h);
    }
  }
  return g;
}

/// Largest column norm: the scale relative errors are measured against.
inline double MaxNorm(const Matrix3X& f) { return f.colwise().norm().maxCoeff(); }

/// |sum f_i| / sum |f_i| and |sum x_i x f_i| / sum |x_i||f_i|: both 0 for an
/// internal force (momentum and angular momentum conserved).
struct Balance {
  double force = 0.0, torque = 0.0;
};
inline Balance NetForceAndTorque(const System& sys, const Matrix3X& f) {
  double f_scale = 0.0, t_scale = 0.0;
  Vec3 net = Vec3::Zero(), torque = Vec3::Zero();
  for (Index i = 0; i < sys.size(); ++i) {
    net += f.col(i);
    torque += sys.positions().col(i).cross(f.col(i));
    f_scale += f.col(i).norm();
    t_scale += sys.positions().col(i).norm() * f.col(i).norm();
  }
  return {net.norm() / f_scale, torque.norm() / t_scale};
}

}  // namespace pdyn::test
