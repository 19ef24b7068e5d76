// lennard_jones through the pair-force SDK (pdyn/pair.hpp): the analytic
// law for two particles, the neighbor-list sum equal to a brute-force sum
// over all pairs (open and periodic), bit-identical forces for 1-4 threads,
// energy conservation of a small Lennard-Jones liquid under velocity
// Verlet, the cutoff that does not fit a periodic box refused naming the
// key, and a blow-up (two particles on top of each other) naming the force.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "pdyn/error.hpp"
#include "pdyn/parallel.hpp"
#include "pdyn/resolve.hpp"
#include "pdyn/system.hpp"
#include "support/physics_support.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

const PluginDescriptor& lj() {
  return *test::shipped_plugins().find(PluginKind::Force, "lennard_jones")->descriptor;
}

// A lennard_jones object for the particles of `sys`, with `given` parameters.
std::unique_ptr<Force> make(const System& sys, const Params& given) {
  const Resolved r = resolve(lj().params, given);
  EXPECT_TRUE(r.problems.empty());
  return lj().create_force(r.params, SceneContext{sys.view(), nullptr});
}

void set(System& sys, const Matrix3X& x) {
  sys.set_particles(x, Matrix3X::Zero(3, x.cols()), Eigen::VectorXd::Ones(x.cols()),
                    std::vector<std::uint8_t>(static_cast<std::size_t>(x.cols()), 0));
}

Matrix3X forces(Force& f, const System& sys) {
  Matrix3X out = Matrix3X::Zero(3, sys.size());
  f.add_forces(sys.view(), out);
  return out;
}

TEST(LennardJones, TwoParticlesFollowTheAnalyticLaw) {
  const double eps = 0.7, sigma = 1.3, rc = 2.5 * sigma;
  Params given;
  given.set("epsilon", eps);
  given.set("sigma", sigma);
  given.set("cutoff", rc);
  for (const double r :
       {0.95 * sigma, std::pow(2.0, 1.0 / 6.0) * sigma, 1.5 * sigma, 3.0 * sigma, rc + 0.01}) {
    System sys;
    Matrix3X x = Matrix3X::Zero(3, 2);
    x.col(1) = r * Vec3(0.6, 0.0, 0.8);
    set(sys, x);
    auto force = make(sys, given);
    const Matrix3X f = forces(*force, sys);
    const double sr6 = std::pow(sigma / r, 6.0);
    const bool inside = r < rc;
    const double u = inside ? 4 * eps * (sr6 * sr6 - sr6) : 0.0;
    const double fr = inside ? 24 * eps * (2 * sr6 * sr6 - sr6) / r : 0.0;  // -U'(r), N
    // On particle 1 (at +r n), the force is +fr along n: repulsive when fr > 0.
    EXPECT_NEAR((Vec3(f.col(1)) - fr * Vec3(0.6, 0.0, 0.8)).norm(), 0.0, 1e-12 * (1 + std::abs(fr)))
        << "r = " << r;
    EXPECT_EQ(Vec3(f.col(0) + f.col(1)), Vec3::Zero());  // Newton's third law, exactly
    EXPECT_NEAR(*force->potential_energy(sys.view()), u, 1e-13 * (1 + std::abs(u))) << "r = " << r;
  }
  // At the minimum r = 2^(1/6) sigma the force vanishes and U = -eps.
  // With shift on, U(rc^-) -> 0 and the force is unchanged.
  given.set("shift", true);
  System sys;
  Matrix3X x = Matrix3X::Zero(3, 2);
  x(0, 1) = rc * (1 - 1e-9);
  set(sys, x);
  auto shifted = make(sys, given);
  EXPECT_NEAR(*shifted->potential_energy(sys.view()), 0.0, 1e-9);
}

// Forces from the brute-force sum over all pairs, nearest image.
Matrix3X brute_force(const Matrix3X& x, const Domain& d, double eps, double sigma, double rc) {
  Matrix3X f = Matrix3X::Zero(3, x.cols());
  for (Index i = 0; i < x.cols(); ++i) {
    for (Index j = i + 1; j < x.cols(); ++j) {
      const Vec3 r = d.minimum_image(x.col(i) - x.col(j));
      const double r2 = r.squaredNorm();
      if (r2 >= rc * rc) continue;
      const double sr6 = std::pow(sigma * sigma / r2, 3.0);
      const Vec3 fij = 24 * eps * (2 * sr6 * sr6 - sr6) / r2 * r;
      f.col(i) += fij;
      f.col(j) -= fij;
    }
  }
  return f;
}

// A random liquid-like configuration: jittered simple-cubic lattice at
// spacing 1.1 sigma (no two particles much closer than sigma).
Matrix3X lattice(int side, double spacing, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.05, 0.05);
  Matrix3X x(3, side * side * side);
  Index k = 0;
  for (int a = 0; a < side; ++a)
    for (int b = 0; b < side; ++b)
      for (int c = 0; c < side; ++c)
        x.col(k++) =
            spacing * Vec3(a + 0.5 + jitter(rng), b + 0.5 + jitter(rng), c + 0.5 + jitter(rng));
  return x;
}

TEST(LennardJones, NeighborListSumEqualsTheBruteForceSum) {
  for (const bool periodic : {false, true}) {
    SCOPED_TRACE(periodic ? "periodic" : "open");
    const int side = 8;
    const double spacing = 1.1;
    System sys;
    set(sys, lattice(side, spacing, 7));
    Domain d;
    if (periodic) {
      d.min = Vec3::Zero();
      d.max = Vec3::Constant(side * spacing);
      d.periodic = {true, true, true};
      sys.set_domain(d);
    }
    Params given;
    given.set("shift", true);
    auto force = make(sys, given);
    // Move the particles over several steps, so that the list is reused and rebuilt.
    std::mt19937 rng(3);
    std::normal_distribution<double> move(0.0, 0.04);
    for (int step = 0; step < 12; ++step) {
      const Matrix3X f = forces(*force, sys);
      const Matrix3X want = brute_force(sys.positions(), d, 1.0, 1.0, 2.5);
      EXPECT_LE((f - want).cwiseAbs().maxCoeff(), 1e-10 * want.cwiseAbs().maxCoeff())
          << "step " << step;
      for (Index i = 0; i < sys.size(); ++i) {
        sys.positions().col(i) += Vec3(move(rng), move(rng), move(rng));
      }
      sys.wrap_positions();
    }
  }
}

TEST(LennardJones, ForcesAreBitIdenticalForOneToFourThreads) {
  System sys;
  set(sys, lattice(28, 1.1, 11));  // 21,952 particles: the threaded path
  Domain d;
  d.max = Vec3::Constant(28 * 1.1);
  d.periodic = {true, true, true};
  sys.set_domain(d);
  Matrix3X reference;
  for (const int threads : {1, 2, 3, 4}) {
    set_threads(threads);
    auto force = make(sys, Params{});
    Matrix3X f = Matrix3X::Constant(3, sys.size(), 0.125);  // added onto forces already there
    force->add_forces(sys.view(), f);
    if (threads == 1) {
      reference = f;
    } else {
      EXPECT_TRUE(f.cwiseEqual(reference).all()) << threads << " threads";
    }
  }
  set_threads(available_threads());
}

// 256 atoms of an fcc Lennard-Jones liquid (reduced density 0.8442, the
// LAMMPS melt benchmark's), periodic, shifted cutoff 2.5 sigma, velocity
// Verlet over 5 time units. The total energy is bounded (no drift) and its
// worst excursion shrinks as dt^2: the measured order between dt = 0.005
// and 0.0025 is 2 within 0.3.
double worst_energy_error(double dt, int steps) {
  const double a = std::cbrt(4.0 / 0.8442);  // fcc cell side, sigma
  const int cells = 4;
  std::mt19937 rng(5);
  std::normal_distribution<double> vel(0.0, 1.2);
  Vec3 total = Vec3::Zero();
  std::vector<Vec3> xs, vs;
  for (int i = 0; i < cells; ++i)
    for (int j = 0; j < cells; ++j)
      for (int k = 0; k < cells; ++k)
        for (const Vec3& b :
             {Vec3(0, 0, 0), Vec3(0.5, 0.5, 0), Vec3(0.5, 0, 0.5), Vec3(0, 0.5, 0.5)}) {
          xs.push_back(a * (Vec3(i, j, k) + b + Vec3::Constant(0.25)));
          vs.emplace_back(vel(rng), vel(rng), vel(rng));
          total += vs.back();
        }
  std::string particles;
  for (std::size_t i = 0; i < xs.size(); ++i) {
    particles += "  - { position: " + test::Vec(xs[i]) +
                 ", velocity: " + test::Vec(vs[i] - total / static_cast<double>(xs.size())) +
                 ", mass: 1 }\n";
  }
  Scene scene = test::load_text("simulation: { dt: " + test::Num(dt) +
                                ", steps: 1, solver: { type: verlet } }\nparticles:\n" + particles +
                                "forces:\n  - { type: lennard_jones, shift: true }\n");
  System& sys = *scene.system;
  Domain d;
  d.max = Vec3::Constant(cells * a);
  d.periodic = {true, true, true};
  sys.set_domain(d);
  const double e0 = sys.kinetic_energy() + sys.potential_energy();
  double worst = 0.0;
  for (int k = 1; k <= steps; ++k) {
    test::TakeStep(scene, k, dt);
    worst = std::max(worst, std::abs(sys.kinetic_energy() + sys.potential_energy() - e0));
  }
  EXPECT_GE(sys.positions().minCoeff(), 0.0);  // every particle still in the box
  EXPECT_LT(sys.positions().maxCoeff(), cells * a);
  return worst / static_cast<double>(sys.size());
}

TEST(LennardJones, SmallLiquidConservesEnergyToSecondOrder) {
  const double coarse = worst_energy_error(0.005, 1000), fine = worst_energy_error(0.0025, 2000);
  const double order = std::log2(coarse / fine);
  std::cout << "LJ liquid, 256 atoms, 5 time units: worst |E - E0| per atom " << coarse
            << " eps (dt 0.005), " << fine << " eps (dt 0.0025): order " << order << "\n";
  EXPECT_LT(coarse, 2e-3);
  EXPECT_NEAR(order, 2.0, 0.3);
}

TEST(LennardJones, ACutoffThatDoesNotFitThePeriodicBoxIsRefused) {
  System sys;
  set(sys, lattice(2, 1.1, 1));
  Domain d;
  d.max = Vec3(10, 5, 10);
  d.periodic = {true, true, false};
  sys.set_domain(d);
  try {
    make(sys, Params{});
    ADD_FAILURE() << "no error";
  } catch (const ParamError& e) {
    EXPECT_EQ(e.param(), "cutoff");
    EXPECT_EQ(std::string(e.what()),
              "2.5 m with skin 0.3 m does not fit the periodic box: its y side is 5 m (expected a "
              "side of at least 2 (cutoff + skin) = 5.6 m)");
  }
}

TEST(LennardJones, TwoParticlesOnTopOfEachOtherStopTheRunNamingTheForce) {
  const auto dir = test::temp_dir("lj-blowup");
  test::write_file(dir / "scene.yaml",
                   "simulation: { dt: 0.001, steps: 10 }\n"
                   "particles:\n"
                   "  - { position: [0, 0, 0], mass: 1 }\n"
                   "  - { position: [0, 0, 0], mass: 1 }\n"
                   "forces:\n"
                   "  - { type: lennard_jones }\n");
  const auto r =
      test::pdyn({"run", (dir / "scene.yaml").string(), "-q", "--plugin-path", PDYN_PLUGIN_DIR});
  EXPECT_EQ(r.status, 4) << r.err;
  EXPECT_NE(r.err.find("lennard_jones ("), std::string::npos) << r.err;
}

}  // namespace
}  // namespace pdyn
