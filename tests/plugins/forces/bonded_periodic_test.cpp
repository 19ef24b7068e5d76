// Bonded terms across a periodic face (BondedForce, since 0.10.0): each
// term is measured with its particles at their images nearest the term's
// first particle, as LAMMPS measures a bond to its partner's closest image.
//  - one spring across the x face: the force, energy, virial and default
//    rest length of the 0.1 m bond, not of the 0.9 m straight segment;
//  - a chain of springs, angles and a dihedral straddling the face moves as
//    the same chain in open space (positions unwrapped with the image
//    counts agree to rounding after 2000 rk4 steps);
//  - terms away from the faces read their particles bit for bit.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <string>

#include "pdyn/host/assembly.hpp"
#include "pdyn/system.hpp"
#include "pdyn/thermo.hpp"
#include "support/physics_support.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

Matrix3X PeriodicForcesOf(const System& sys, std::size_t index) {
  Matrix3X f = Matrix3X::Zero(3, sys.size());
  sys.force_objects().at(index).force->add_forces(sys.view(), f);
  return f;
}

constexpr const char* kBoxX =
    "  box: { min: [0, 0, 0], max: [1, 1, 1], periodic: [true, false, false] }\n";

TEST(BondedPeriodic, ASpringAcrossTheFaceIsTheShortBond) {
  // x = 0.05 and 0.95 in a box of length 1: the nearest images are 0.1 m
  // apart. With rest 0.2 the bond is compressed by 0.1: |f| = ks 0.1 = 0.8 N,
  // particle 0 pushed towards +x (its partner's image is at -0.05), U = ks
  // 0.1^2 / 2 = 0.04 J, virial (x1' - x0) . f1 = (-0.1)(-0.8) = 0.08 J.
  Scene scene = test::load_text(std::string("simulation:\n  dt: 0.001\n  steps: 1\n") + kBoxX +
                                R"(particles:
  - { position: [0.05, 0.5, 0.5], mass: 1 }
  - { position: [0.95, 0.5, 0.5], mass: 1 }
forces:
  - { type: spring, pairs: [[0, 1]], ks: 8, rest: [0.2] }
  - { type: spring, pairs: [[1, 0]], ks: 8 }
)");
  const System& sys = *scene.system;
  const Matrix3X f = PeriodicForcesOf(sys, 0);
  EXPECT_NEAR((f.col(0) - Vec3(0.8, 0, 0)).norm(), 0.0, 1e-14);
  EXPECT_NEAR((f.col(1) + Vec3(0.8, 0, 0)).norm(), 0.0, 1e-14);
  const Force& spring = *sys.force_objects().at(0).force;
  EXPECT_NEAR(spring.potential_energy(sys.view()).value(), 0.04, 1e-15);
  const auto* virial = dynamic_cast<const VirialSource*>(&spring);
  ASSERT_NE(virial, nullptr);
  EXPECT_NEAR(virial->virial(sys.view()), 0.08, 1e-15);
  // The default rest length is the initial nearest-image distance, 0.1 m
  // (measured from particle 1 this time): no force at the start.
  EXPECT_EQ(PeriodicForcesOf(sys, 1), Matrix3X::Zero(3, 2));
  EXPECT_NEAR(sys.force_objects().at(1).force->potential_energy(sys.view()).value(), 0.0, 1e-30);
}

// Four particles across the face x = 0 (= 2) of a box periodic along x, or
// the same four unwrapped in open space: springs between neighbours, the
// two angles and the dihedral, swinging under their initial velocities and
// drifting along +x at 0.5 m/s, so that the first two cross the face.
std::string Chain(bool periodic) {
  const double x_box[4] = {1.92, 1.97, 0.04, 0.1}, x_open[4] = {1.92, 1.97, 2.04, 2.1};
  const double y[4] = {0.4, 0.52, 0.47, 0.6}, z[4] = {0.5, 0.45, 0.55, 0.52};
  const char* v[4] = {"[0.8, -0.2, 0.1]", "[0.1, 0.1, 0.2]", "[0.6, 0.3, -0.3]",
                      "[0.7, -0.1, 0.4]"};
  std::string yaml = "simulation:\n  dt: 0.0005\n  steps: 1\n  solver: { type: rk4 }\n";
  if (periodic) {
    yaml += "  box: { min: [0, 0, 0], max: [2, 1, 1], periodic: [true, false, false] }\n";
  }
  yaml += "particles:\n";
  for (int i = 0; i < 4; ++i) {
    yaml += "  - { position: [" + test::Num(periodic ? x_box[i] : x_open[i]) + ", " +
            test::Num(y[i]) + ", " + test::Num(z[i]) + "], velocity: " + v[i] +
            ", mass: " + std::to_string(1 + i) + " }\n";
  }
  yaml += R"(forces:
  - { type: spring, pairs: [[0, 1], [1, 2], [2, 3]], ks: 400, kd: 0.1, rest: [0.1] }
  - { type: angle, triples: [[0, 1, 2], [1, 2, 3]], k: 2, rest: [2.5] }
  - { type: dihedral, quads: [[0, 1, 2, 3]], k: 0.5, rest: [0.3] }
)";
  return yaml;
}

TEST(BondedPeriodic, AChainAcrossTheFaceMovesAsInOpenSpace) {
  Scene boxed = test::load_text(Chain(true));
  Scene open = test::load_text(Chain(false));
  System& a = *boxed.system;
  System& b = *open.system;
  ASSERT_NEAR(a.potential_energy(), b.potential_energy(), 1e-12 * std::abs(b.potential_energy()));
  ASSERT_GT(std::abs(b.potential_energy()), 0.01) << "the chain should start away from rest";
  // The open chain's last two particles start one box length (2 m) on.
  const double shift[4] = {0.0, 0.0, 2.0, 2.0};
  double worst = 0.0;
  for (int step = 0; step < 2000; ++step) {
    boxed.solver->step(a, 0.0005);
    SystemAssembly(a).wrap_positions();
    open.solver->step(b, 0.0005);
    for (Index i = 0; i < 4; ++i) {
      const double images = 2.0 * a.images()[static_cast<std::size_t>(i)][0] + shift[i];
      const Vec3 unwrapped = a.positions().col(i) + Vec3(images, 0.0, 0.0);
      worst = std::max(worst, (unwrapped - b.positions().col(i)).norm());
    }
  }
  std::cout << "chain across the face, 2000 rk4 steps: max |x_box - x_open| = " << worst
            << " m; boxed energy " << a.potential_energy() << " J, open " << b.potential_energy()
            << " J\n";
  int wrapped = 0;
  for (const auto& n : a.images()) wrapped += n[0] != 0;
  EXPECT_EQ(wrapped, 2) << "the first two particles should cross the face";
  // Rounding only: the boxed run adds and subtracts the box length.
  EXPECT_LE(worst, 1e-12);
  EXPECT_NEAR(a.potential_energy(), b.potential_energy(), 1e-11);
}

TEST(BondedPeriodic, TermsAwayFromTheFacesReadTheirParticlesBitForBit) {
  // The same chain, translated to the middle of the box: with and without
  // the box every force is the same to the last bit.
  std::string boxed = Chain(false), open = Chain(false);
  boxed.replace(boxed.find("particles:"), 0,
                "  box: { min: [0, 0, 0], max: [3, 3, 3], periodic: [true, true, true] }\n");
  ASSERT_NE(boxed, open);
  Scene a = test::load_text(boxed);
  Scene b = test::load_text(open);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(PeriodicForcesOf(*a.system, k), PeriodicForcesOf(*b.system, k)) << "force " << k;
  }
  EXPECT_EQ(a.system->potential_energy(), b.system->potential_energy());
}

}  // namespace
}  // namespace pdyn
