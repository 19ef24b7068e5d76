// The particle builders chain, lattice, cloud, ring and polygon
// (host/src/scene_builders.cpp, docs/scenes.md): particle counts and
// numbering, the springs each makes (read back from the real spring objects
// through their Jacobians: every pair (i, j) contributes one df_i/dx_j
// block with i < j), rest lengths equal to the initial distances (zero
// potential energy at the initial state), reproducible clouds, and bad keys
// refused with located messages.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <iostream>
#include <map>
#include <numbers>
#include <set>

#include "pdyn/bonded_reference.hpp"
#include "support/physics_support.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

using PairSet = std::multiset<std::pair<Index, Index>>;

class PairRecorder final : public JacobianSink {
 public:
  void add_dfdx(Index i, Index j, const Eigen::Matrix3d&) override {
    if (i < j) pairs.insert({i, j});
  }
  void add_dfdv(Index, Index, const Eigen::Matrix3d&) override {}
  PairSet pairs;
};

// The pairs of every force object whose label starts with `plugin`, in order.
std::vector<PairSet> SpringPairs(const Scene& scene) {
  std::vector<PairSet> out;
  for (const auto& e : scene.system->force_objects()) {
    if (e.label.rfind("spring ", 0) != 0) continue;
    PairRecorder r;
    EXPECT_TRUE(e.force->add_jacobians(scene.system->view(), r));
    out.push_back(r.pairs);
  }
  return out;
}

int CountObjects(const Scene& scene, const std::string& plugin) {
  int n = 0;
  for (const auto& e : scene.system->force_objects()) n += e.label.rfind(plugin + " ", 0) == 0;
  return n;
}

double Length(const Scene& s, const std::pair<Index, Index>& p) {
  return (s.system->positions().col(p.first) - s.system->positions().col(p.second)).norm();
}

std::string Head(const std::string& particles) {
  return "simulation: { dt: 0.001, steps: 1 }\nparticles:\n" + particles;
}

std::string Error(const std::string& yaml) {
  try {
    test::load_text(yaml);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "(loaded without error)";
}

TEST(ChainBuilder, MakesNEvenlySpacedParticlesAndNeighbourSprings) {
  Scene s = test::load_text(Head(
      "  - { position: [5, 5, 5], mass: 1 }\n"
      "  - chain: { from: [0, 0, 2], to: [1, 0, 2], n: 20, mass: 0.01, name: rope, pin: [0, -1],\n"
      "             springs: { ks: 500, kd: 0.2 } }\n"));
  ASSERT_EQ(s.system->size(), 21);
  for (Index i = 0; i < 20; ++i) {
    EXPECT_NEAR((s.system->positions().col(1 + i) - Vec3(i / 19.0, 0, 2)).norm(), 0.0, 1e-15);
    EXPECT_EQ(s.system->masses()(1 + i), 0.01);
    EXPECT_EQ(s.system->fixed()[1 + i] != 0, i == 0 || i == 19) << i;
  }
  const auto springs = SpringPairs(s);
  ASSERT_EQ(springs.size(), 1u);
  PairSet expected;
  for (Index i = 1; i < 20; ++i) expected.insert({i, i + 1});
  EXPECT_EQ(springs[0], expected);
  EXPECT_EQ(s.system->potential_energy(), 0.0);  // rest lengths = initial distances
  ASSERT_EQ(s.groups.count("rope"), 1u);
  EXPECT_EQ(s.groups.at("rope").front(), 1);
  EXPECT_EQ(s.groups.at("rope").size(), 20u);
}

// bend: angle springs on (i-1, i, i+1). Bending the straight chain into a
// circular arc turns every interior angle by the same d, so the angle
// object's energy k/2 sum (theta - theta0)^2 counts the triples: (n-2) k d^2/2.
TEST(ChainBuilder, BendMakesAngleSpringsOnConsecutiveTriples) {
  constexpr int kN = 20;
  constexpr double kK = 1.0;
  Scene s = test::load_text(
      Head("  - chain: { from: [0, 0, 2], to: [1, 0, 2], n: 20, mass: 0.01, bend: { k: 1 } }\n"));
  ASSERT_EQ(CountObjects(s, "angle"), 1);
  ASSERT_EQ(CountObjects(s, "spring"), 1);
  EXPECT_NEAR(s.system->potential_energy(), 0.0, 1e-12);
  const double d = 0.05;  // rad per joint
  for (Index i = 0; i < kN; ++i) {
    s.system->positions().col(i) = Vec3(std::sin(i * d), 1.0 - std::cos(i * d), 2.0);
  }
  double u_angle = 0.0;
  for (const auto& e : s.system->force_objects()) {
    if (e.label.rfind("angle ", 0) == 0) u_angle = *e.force->potential_energy(s.system->view());
  }
  const double triples = u_angle / (0.5 * kK * d * d);
  std::cout << "chain bend: angle energy " << u_angle << " J = " << triples
            << " x k d^2 / 2 (expected " << kN - 2 << ")\n";
  EXPECT_NEAR(triples, kN - 2, 1e-6);
}

// A 7 x 5 grid with `bending`: one dihedral object with a hinge on every
// interior edge of the triangulated sheet, (nx-1)(ny-1) diagonals +
// (nx-1)(ny-2) row edges + (nx-2)(ny-1) column edges, at rest when flat.
// Rolled onto a cylinder of radius R whose axis runs along v, neighbours
// along u a chord h apart, each column strip stays a flat facet and adjacent
// facets meet at the angle theta = 2 asin(h / 2R): only the column edges
// bend, each by theta, so U = (nx-2)(ny-1) k theta^2 / 2.
TEST(GridBuilder, BendingPutsADihedralOnEveryInteriorEdge) {
  constexpr std::int64_t kNx = 7, kNy = 5;
  constexpr double kK = 0.3, kH = 0.1, kR = 0.4;
  Scene s = test::load_text(
      Head("  - grid: { origin: [0, 0, 0], u: [0.1, 0, 0], v: [0, 0.1, 0], nx: 7, ny: 5, "
           "mass: 0.01, bending: { k: 0.3 } }\n"));
  ASSERT_EQ(CountObjects(s, "dihedral"), 1);
  const BondedReference* hinges = nullptr;
  for (const auto& e : s.system->force_objects()) {
    if (e.label.rfind("dihedral ", 0) == 0)
      hinges = dynamic_cast<const BondedReference*>(e.force.get());
  }
  ASSERT_NE(hinges, nullptr);
  EXPECT_EQ(hinges->bonded_terms(),
            (kNx - 1) * (kNy - 1) + (kNx - 1) * (kNy - 2) + (kNx - 2) * (kNy - 1));
  EXPECT_NEAR(s.system->potential_energy(), 0.0, 1e-24);
  const double theta = 2.0 * std::asin(kH / (2.0 * kR));
  for (std::int64_t j = 0; j < kNy; ++j) {
    for (std::int64_t i = 0; i < kNx; ++i) {
      const double a = static_cast<double>(i) * theta;
      s.system->positions().col(j * kNx + i) =
          Vec3(kR * std::sin(a), static_cast<double>(j) * kH, kR * (1.0 - std::cos(a)));
    }
  }
  const double expected = static_cast<double>((kNx - 2) * (kNy - 1)) * 0.5 * kK * theta * theta;
  std::cout << "grid bending on a cylinder: U = " << s.system->potential_energy() << " J, expected "
            << expected << " J\n";
  EXPECT_NEAR(s.system->potential_energy(), expected, 1e-12 * expected);
}

TEST(LatticeBuilder, MakesStructuralAndShearSpringsByDefault) {
  Scene s = test::load_text(Head(
      "  - lattice: { origin: [0, 0, 1], n: [3, 4, 5], spacing: 0.1, mass: 0.01, name: jelly,\n"
      "               pin: [[0, 0, 0], [-1, -1, -1]] }\n"));
  ASSERT_EQ(s.system->size(), 60);
  // id = (k ny + j) nx + i
  EXPECT_NEAR((s.system->positions().col((4 * 4 + 2) * 3 + 1) - Vec3(0.1, 0.2, 1.4)).norm(), 0.0,
              1e-15);
  EXPECT_TRUE(s.system->fixed()[0]);
  EXPECT_TRUE(s.system->fixed()[59]);
  EXPECT_EQ(std::count(s.system->fixed().begin(), s.system->fixed().end(), 1), 2);
  const auto springs = SpringPairs(s);
  ASSERT_EQ(springs.size(), 2u);
  EXPECT_EQ(springs[0].size(), 2u * 4 * 5 + 3 * 3 * 5 + 3 * 4 * 4);        // 133
  EXPECT_EQ(springs[1].size(), 2u * (2 * 3 * 5 + 2 * 4 * 4 + 3 * 4 * 3));  // 196
  for (const auto& p : springs[0]) ASSERT_NEAR(Length(s, p), 0.1, 1e-12);
  for (const auto& p : springs[1]) ASSERT_NEAR(Length(s, p), 0.1 * std::sqrt(2.0), 1e-12);
  EXPECT_EQ(std::set(springs[1].begin(), springs[1].end()).size(), springs[1].size());
  EXPECT_EQ(s.system->potential_energy(), 0.0);
}

TEST(LatticeBuilder, SpringsListsExactlyTheFamiliesWanted) {
  Scene s = test::load_text(
      Head("  - lattice: { origin: [0, 0, 1], n: [3, 4, 5], spacing: 0.1, mass: 0.01,\n"
           "               springs: { body: { ks: 5 } } }\n"));
  const auto springs = SpringPairs(s);
  ASSERT_EQ(springs.size(), 1u);
  EXPECT_EQ(springs[0].size(), 4u * 2 * 3 * 4);  // 96
  for (const auto& p : springs[0]) ASSERT_NEAR(Length(s, p), 0.1 * std::sqrt(3.0), 1e-12);
}

// `rods:` makes one `distance` constraint per family it lists (the springs'
// pairs) and, without `springs:`, no default springs; every rod starts at
// its length. A spinning cube of structural, shear and body rods (28 rods
// for its 18 degrees of freedom: redundant) dropped under XPBD moves as a
// rigid body: its centre of mass follows the free fall of the integrator's
// substeps to 1e-9 m (the rods' corrections are internal) and no rod strays from its length by
// more than 1e-9 of the edge.
TEST(LatticeBuilder, RodsMakeDistanceConstraintsOfTheListedFamilies) {
  Scene s = test::load_text(
      Head("  - lattice: { origin: [0, 0, 1], n: [3, 4, 5], spacing: 0.1, mass: 0.01,\n"
           "               rods: { structural: { compliance: 0 }, body: { compliance: 0 } } }\n"));
  EXPECT_EQ(SpringPairs(s).size(), 0u);
  const auto& constraints = s.system->constraint_objects();
  ASSERT_EQ(constraints.size(), 2u);
  EXPECT_EQ(constraints[0].label.rfind("distance ", 0), 0u) << constraints[0].label;
  EXPECT_EQ(s.system->constraint_rows(), 133 + 96);
  EXPECT_LT(s.system->constraint_error(), 1e-15);

  Scene both = test::load_text(
      Head("  - lattice: { origin: [0, 0, 1], n: [3, 4, 5], spacing: 0.1, mass: 0.01,\n"
           "               rods: { shear: { compliance: 0 } }, springs: { body: { ks: 5 } } }\n"));
  ASSERT_EQ(SpringPairs(both).size(), 1u);
  EXPECT_EQ(SpringPairs(both)[0].size(), 96u);
  EXPECT_EQ(both.system->constraint_rows(), 196);
}

TEST(LatticeBuilder, ACubeOfRodsFallsRigidUnderXpbd) {
  const double dt = 0.001, g = 9.81;
  Scene s = test::load_text(
      "simulation: { dt: 0.001, steps: 300, solver: { type: xpbd, substeps: 4 } }\n"
      "particles:\n"
      "  - lattice: { origin: [0, 0, 1], n: [2, 2, 2], spacing: 0.1, mass: 0.01,\n"
      "               velocity: [0, 0, 0.5],\n"
      "               rods: { structural: { compliance: 0 }, shear: { compliance: 0 },\n"
      "                       body: { compliance: 0 } } }\n"
      "forces:\n  - { type: gravity }\n");
  ASSERT_EQ(s.system->constraint_rows(), 12 + 12 + 4);
  System& sys = *s.system;
  // Spin it a little so that the rods have work to do: v = w x (x - c).
  const Vec3 c0 = sys.positions().rowwise().mean();
  for (Index i = 0; i < sys.size(); ++i) {
    sys.velocities().col(i) += Vec3(0.0, 3.0, 1.0).cross(Vec3(sys.positions().col(i) - c0));
  }
  const Vec3 v0 = sys.velocities().rowwise().mean();
  double worst = 0.0;
  for (int k = 1; k <= 300; ++k) {
    test::TakeStep(s, k, dt);
    worst = std::max(worst, sys.constraint_error());
  }
  // XPBD's substeps are symplectic Euler steps for the centre of mass:
  // v += h g, then x += h v, M times, h = dt / 4.
  const double h = dt / 4, m = 4 * 300;
  const Vec3 expected = c0 + (m * h) * v0 - Vec3(0, 0, g * h * h * m * (m + 1) / 2);
  // 5e-11 m measured: rounding, which the velocity update (x - x_prev) / h
  // divides by the 0.25 ms substep; a momentum the rods did not conserve
  // would be millimetres.
  EXPECT_LT((Vec3(sys.positions().rowwise().mean()) - expected).norm(), 1e-9);
  EXPECT_LT(worst, 1e-10);  // m: 1e-9 of the 0.1 m edge
}

TEST(CloudBuilder, IsReproducibleFromItsSeedAndInsideItsRegion) {
  auto cloud = [](int seed, const std::string& region) {
    return test::load_text(Head("  - cloud: { n: 1000, " + region + ", mass: 0.001, seed: " +
                                std::to_string(seed) + ", name: cloud }\n"));
  };
  const std::string box = "box: { min: [-1, -1, 1], max: [1, 1, 2] }";
  Scene a = cloud(7, box), b = cloud(7, box), c = cloud(8, box);
  ASSERT_EQ(a.system->size(), 1000);
  EXPECT_EQ(a.system->state(), b.system->state());
  EXPECT_NE(a.system->positions(), c.system->positions());
  const Matrix3X& x = a.system->positions();
  EXPECT_GE(x.row(0).minCoeff(), -1.0);
  EXPECT_LT(x.row(0).maxCoeff(), 1.0);
  EXPECT_GE(x.row(2).minCoeff(), 1.0);
  EXPECT_LT(x.row(2).maxCoeff(), 2.0);
  // Uniform: the mean is the box centre within 3.3 standard errors (0.58 /
  // sqrt(1000) = 0.018 m for x and y, 0.009 m for z).
  const Vec3 mean = x.rowwise().mean();
  std::cout << "cloud of 1000 in the box: mean " << mean.transpose() << "\n";
  EXPECT_LT((mean - Vec3(0, 0, 1.5)).cwiseAbs().maxCoeff(), 0.06);
  EXPECT_EQ(CountObjects(a, "spring"), 0);

  Scene ball = cloud(7, "sphere: { center: [1, 2, 3], radius: 0.5 }");
  const double r_max =
      (ball.system->positions().colwise() - Vec3(1, 2, 3)).colwise().norm().maxCoeff();
  // Uniform in a ball: the fraction within r/2 is 1/8.
  const auto inner =
      ((ball.system->positions().colwise() - Vec3(1, 2, 3)).colwise().norm().array() < 0.25)
          .count();
  std::cout << "cloud of 1000 in the ball: max radius " << r_max << ", " << inner
            << " within half the radius (expected ~125)\n";
  EXPECT_LE(r_max, 0.5);
  EXPECT_NEAR(static_cast<double>(inner), 125.0, 35.0);
}

// ring: n particles on a circle, ring springs (i, i+1 mod n), and with
// `area` the fan of triangles (0, i, i+1). Scaling the ring by s about its
// centre scales every area by s^2: U = k/2 sum_t ((s^2 - 1) A_t)^2, which
// the test predicts from the fan's own triangles.
TEST(RingBuilder, MakesAClosedLoopAndAFanOfAreaTriangles) {
  constexpr int kN = 24;
  constexpr double kR = 0.2, kK = 50.0;
  Scene s = test::load_text(Head(
      "  - ring: { center: [0, 0, 1], radius: 0.2, n: 24, mass: 0.01, name: blob, area: { k: 50 } "
      "}\n"));
  ASSERT_EQ(s.system->size(), kN);
  const Vec3 c(0, 0, 1);
  for (Index i = 0; i < kN; ++i) {
    const double t = 2 * std::numbers::pi * i / kN;
    ASSERT_NEAR(
        (s.system->positions().col(i) - (c + kR * Vec3(std::cos(t), std::sin(t), 0))).norm(), 0.0,
        1e-15);
  }
  const auto springs = SpringPairs(s);
  ASSERT_EQ(springs.size(), 1u);
  PairSet expected;
  for (Index i = 0; i + 1 < kN; ++i) expected.insert({i, i + 1});
  expected.insert({0, kN - 1});
  EXPECT_EQ(springs[0], expected);
  for (const auto& p : springs[0])
    ASSERT_NEAR(Length(s, p), 2 * kR * std::sin(std::numbers::pi / kN), 1e-15);
  ASSERT_EQ(CountObjects(s, "area"), 1);
  EXPECT_NEAR(s.system->potential_energy(), 0.0, 1e-15);

  double sum_a2 = 0.0;
  const Matrix3X x0 = s.system->positions();
  for (Index i = 1; i + 1 < kN; ++i) {
    const double a = 0.5 * (x0.col(i) - x0.col(0)).cross(x0.col(i + 1) - x0.col(0)).norm();
    sum_a2 += a * a;
  }
  const double scale = 1.1;
  s.system->positions() = ((x0.colwise() - c) * scale).colwise() + c;
  double u_area = 0.0;
  for (const auto& e : s.system->force_objects()) {
    if (e.label.rfind("area ", 0) == 0) u_area = *e.force->potential_energy(s.system->view());
  }
  const double expected_u = 0.5 * kK * std::pow(scale * scale - 1, 2) * sum_a2;
  std::cout << "ring area springs scaled by 1.1: energy " << u_area << " J, fan predicts "
            << expected_u << " J\n";
  EXPECT_NEAR(u_area / expected_u, 1.0, 1e-9);
}

TEST(RingBuilder, LiesInThePlaneOfItsNormal) {
  Scene s = test::load_text(
      Head("  - ring: { center: [1, 2, 3], radius: 0.5, n: 7, normal: [0, 2, 0], mass: 0.01 }\n"));
  for (Index i = 0; i < 7; ++i) {
    const Vec3 d = s.system->positions().col(i) - Vec3(1, 2, 3);
    EXPECT_NEAR(d.y(), 0.0, 1e-15);
    EXPECT_NEAR(d.norm(), 0.5, 1e-15);
  }
}

TEST(PolygonBuilder, ClosesTheLoopThroughItsPoints) {
  Scene s = test::load_text(
      Head("  - polygon: { points: [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], mass: 0.1,\n"
           "               springs: { ks: 10 }, area: { k: 3 } }\n"));
  ASSERT_EQ(s.system->size(), 4);
  const auto springs = SpringPairs(s);
  ASSERT_EQ(springs.size(), 1u);
  EXPECT_EQ(springs[0], (PairSet{{0, 1}, {1, 2}, {2, 3}, {0, 3}}));
  EXPECT_EQ(CountObjects(s, "area"), 1);
}

// Bad keys: located, "what is wrong (what was expected)".
TEST(Builders, RefuseBadKeysWithLocatedMessages) {
  const std::map<std::string, std::string> cases = {
      {"  - chain: { from: [0, 0, 0], to: [1, 0, 0], n: 1, mass: 1 }\n",
       "test.yaml:3:49: particles[0].chain.n: 1 is out of range (expected a whole number >= 2)"},
      {"  - chain: { from: [0, 0, 0], to: [0, 0, 0], n: 3, mass: 1 }\n",
       "test.yaml:3:35: particles[0].chain.to: is the same point as from (expected the other end "
       "of a chain of nonzero length)"},
      {"  - chain: { from: [0, 0, 0], to: [1, 0, 0], n: 3, mass: 1, spring: { ks: 1 } }\n",
       "test.yaml:3:61: unknown key 'spring' in particles[0].chain (did you mean 'springs'? "
       "expected one of: from, to, n, mass, velocity, name, pin, particle_radius, particle_type, "
       "springs, rods, bend)"},
      {"  - chain: { from: [0, 0, 0], to: [1, 0, 0], n: 3, mass: 1, pin: [3] }\n",
       "test.yaml:3:67: particles[0].chain.pin[0]: 3 is outside the chain of 3 particles "
       "(expected -3..2)"},
      {"  - lattice: { origin: [0, 0, 0], n: [2, 2.5, 2], spacing: 0.1, mass: 1 }\n",
       "test.yaml:3:38: particles[0].lattice.n: [2, 2.5, 2] is not three whole numbers (expected "
       "[nx, ny, nz], each a whole number >= 1)"},
      {"  - lattice: { origin: [0, 0, 0], n: [2, 2, 2], spacing: 0.1, mass: 1, springs: { shear: "
       "{ ks: -1 } } }\n",
       "test.yaml:3:96: particles[0].lattice.springs.shear.ks: -1 is out of range (expected a "
       "number >= 0 in N/m)"},
      {"  - cloud: { n: 5, mass: 1 }\n",
       "test.yaml:3:12: particles[0].cloud: no region is given (expected exactly one region: box: "
       "{ min, max } or sphere: { center, radius })"},
      {"  - cloud: { n: 5, mass: 1, box: { min: [0, 0, 0], max: [1, 1, 1] }, sphere: { center: "
       "[0, 0, 0], radius: 1 } }\n",
       "test.yaml:3:78: particles[0].cloud.sphere: both 'box' and 'sphere' are given (expected "
       "exactly one region: box: { min, max } or sphere: { center, radius })"},
      {"  - cloud: { n: 5, mass: 1, box: { min: [0, 0, 0], max: [1, -1, 1] } }\n",
       "test.yaml:3:57: particles[0].cloud.box.max: [1, -1, 1] is below min [0, 0, 0] in some "
       "component (expected max >= min in every component)"},
      {"  - ring: { center: [0, 0, 0], radius: 0, n: 5, mass: 1 }\n",
       "test.yaml:3:40: particles[0].ring.radius: 0 is out of range (expected a number > 0 in m)"},
      {"  - ring: { center: [0, 0, 0], radius: 1, n: 5, mass: 1 }\n"
       "  - chain: { from: [0, 0, 0], to: [1, 0, 0], n: 3, mass: 1, name: a }\n"
       "  - ring: { center: [0, 0, 0], radius: 1, n: 5, mass: 1, name: a }\n",
       "test.yaml:5:64: particles[2].ring.name: group 'a' is already defined (expected a unique "
       "name)"},
      {"  - polygon: { points: [[0, 0, 0], [1, 0, 0]], mass: 1 }\n",
       "test.yaml:3:24: particles[0].polygon.points: has 2 points (expected at least 3 for a "
       "closed loop)"},
      {"  - chain: { from: [0, 0, 0], to: [1, 0, 0], n: 3, mass: 1 }\n    mass: 2\n",
       "test.yaml:3:5: particles[0]: a builder entry holds only its builder (expected { chain: { "
       "... } })"},
  };
  for (const auto& [particles, message] : cases) {
    EXPECT_EQ(Error(Head(particles)), message) << particles;
  }
}

}  // namespace
}  // namespace pdyn
