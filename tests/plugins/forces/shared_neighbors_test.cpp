// Pair forces on one system share a neighbor list (SharedNeighborList in
// pdyn/neighbors.hpp): lennard_jones (cutoff 2.5, skin 0.3) and soft_contact
// (cutoff 2 radius = 1.0, skin 0.1) in one periodic liquid use one list
// built at cutoff 2.5 and reach 2.8, binned and searched once per rebuild,
// and each force is bit for bit what it is alone in its own system. Forces
// in separate systems never share.
#include <gtest/gtest.h>

#include <string>

#include "force_support.hpp"
#include "pdyn/host/stepper.hpp"
#include "pdyn/pair.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

// 512 particles on a jittered simple-cubic lattice of spacing 1.2 in a
// periodic box of 9.6, moving at up to 1 per unit time along each axis.
std::string SceneText(const std::string& forces) {
  std::string particles;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.05, 0.05), speed(-1.0, 1.0);
  for (int a = 0; a < 8; ++a) {
    for (int b = 0; b < 8; ++b) {
      for (int c = 0; c < 8; ++c) {
        particles += "  - { position: " +
                     test::Vec(Vec3(0.6 + 1.2 * a + jitter(rng), 0.6 + 1.2 * b + jitter(rng),
                                    0.6 + 1.2 * c + jitter(rng))) +
                     ", velocity: " + test::Vec(Vec3(speed(rng), speed(rng), speed(rng))) +
                     ", mass: 1, radius: 0.5 }\n";
      }
    }
  }
  return "simulation: { dt: 0.002, steps: 1, solver: { type: verlet }, box: { min: [0, 0, 0], "
         "max: [9.6, 9.6, 9.6], periodic: [true, true, true] } }\n"
         "particles:\n" +
         particles + "forces:\n" + forces;
}

const std::string kLennardJones = "  - { type: lennard_jones, cutoff: 2.5, skin: 0.3 }\n";
const std::string kContact =
    "  - { type: soft_contact, stiffness: 1000, restitution: 0.5, skin: 0.1 }\n";

const NeighborList* ListOf(const System& sys, std::size_t index) {
  const auto* pair = dynamic_cast<const PairReference*>(sys.force_objects().at(index).force.get());
  return pair ? pair->pair_neighbors() : nullptr;
}

TEST(SharedNeighbors, TwoPairForcesOnOneSystemUseOneListAndGiveTheirOwnForces) {
  Scene both = test::load_text(SceneText(kLennardJones + kContact));
  Scene lj = test::load_text(SceneText(kLennardJones));
  Scene contact = test::load_text(SceneText(kContact));
  for (Scene* s : {&both, &lj, &contact}) {
    Stepper stepper(*s->system, *s->solver, s->solver_label);
    for (int k = 1; k <= 200; ++k) ASSERT_TRUE(stepper.step_to(k * 0.002).has_value()) << k;
  }
  // Not bit-identical states: the sums of two forces differ from one. Each
  // force, evaluated on the combined run's positions, against the same force
  // alone in a system of its own with those positions.
  const System& sys = *both.system;
  lj.system->positions() = sys.positions();
  lj.system->velocities() = sys.velocities();
  contact.system->positions() = sys.positions();
  contact.system->velocities() = sys.velocities();
  EXPECT_EQ(test::ForcesOf(sys, 0), test::ForcesOf(*lj.system, 0));
  EXPECT_EQ(test::ForcesOf(sys, 1), test::ForcesOf(*contact.system, 0));
  EXPECT_GT(test::ForcesOf(sys, 1).cwiseAbs().maxCoeff(), 0.0);  // some balls touch

  const NeighborList* shared = ListOf(sys, 0);
  ASSERT_NE(shared, nullptr);
  EXPECT_EQ(ListOf(sys, 1), shared);
  EXPECT_EQ(shared->cutoff(), 2.5);
  EXPECT_DOUBLE_EQ(shared->reach(), 2.8);
  EXPECT_GT(shared->builds(), 1);  // it rebuilt while the particles moved
  // Separate systems, separate lists.
  EXPECT_NE(ListOf(*lj.system, 0), shared);
  EXPECT_NE(ListOf(*contact.system, 0), shared);
  EXPECT_NE(ListOf(*lj.system, 0), ListOf(*contact.system, 0));
  EXPECT_EQ(ListOf(*contact.system, 0)->cutoff(), 1.0);
}

}  // namespace
}  // namespace pdyn
