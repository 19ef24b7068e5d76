// nose_hoover: velocity Verlet in a Nose-Hoover chain (MTK 1996, as LAMMPS's
// fix nvt). LAMMPS's 256-atom Lennard-Jones melt, started at T* = 1.44,
// holds k_B T = 1 within its statistical error and conserves the extended
// energy K + U + reservoir; one force evaluation per step with the same bits
// as two; the same bits for 1 and 2 threads and across a resume; with the
// chain inert (N_f = 0) the bits are verlet's; the checkpoint bytes are
// checked; each bad parameter gets its located error.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <memory>
#include <random>

#include "host/resume_support.hpp"
#include "pdyn/error.hpp"
#include "pdyn/host/assembly.hpp"
#include "pdyn/host/stepper.hpp"
#include "pdyn/host/threads.hpp"
#include "pdyn/parallel.hpp"
#include "pdyn/system.hpp"
#include "pdyn/thermo.hpp"
#include "plugins/solvers/solver_support.hpp"
#include "support/physics_support.hpp"
#include "support/statistics.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

double NhReservoir(const Scene& scene) {
  return total_reservoir_energy(*scene.system, scene.solver.get());
}

bool NhSameBits(const Scene& a, const Scene& b) {
  return test::same_bits(a.system->state(), b.system->state()) &&
         a.system->time() == b.system->time();
}

// LAMMPS's melt (tests/scenes/thermo): 256 atoms on fcc at density 0.8442,
// T* = 1.44, in its periodic box; the potential shifted to 0 at the cutoff,
// so that the energy is continuous.
Scene NhLiquid(const std::string& solver) { return test::LjLiquid(solver, "", true); }

TEST(NoseHoover, ALiquidHoldsTheTargetTemperatureAndConservesTheExtendedEnergy) {
  // tau = 0.5 = 100 steps, as LAMMPS suggests; 4000 steps = 40 tau.
  Scene scene = NhLiquid("{ type: nose_hoover, kT: 1, tdamp: 0.5 }");
  const System& s = *scene.system;
  const double n = static_cast<double>(s.size());
  ASSERT_EQ(NhReservoir(scene), 0.0);
  const double h0 = s.kinetic_energy() + s.potential_energy();
  const double kt0 = thermo(s.view(), 0.0).kT;
  std::vector<double> kt;
  double worst = 0.0, last = 0.0;
  const std::int64_t steps = 4000;
  test::StepThrough(scene, steps, [&](std::int64_t k) {
    if (k > steps / 2) kt.push_back(thermo(s.view(), 0.0).kT);
    if (k % 10 == 0) {
      last = (s.kinetic_energy() + s.potential_energy() + NhReservoir(scene) - h0) / n;
      worst = std::max(worst, std::abs(last));
    }
  });
  EXPECT_EQ(s.force_evaluations(), static_cast<std::uint64_t>(steps + 1));
  // Blocks of 200 steps (2 tau): the error estimate has reached its plateau
  // there (0.0100 to 0.0108 for 4 to 10 blocks), while shorter blocks,
  // correlated by the thermostat's oscillation (period about 2 pi tau /
  // sqrt(2)), understate it (0.0082 for 20 blocks, 0.0042 for 100).
  const test::MeanError m = test::block_average(kt, 10);
  std::cout << "nose_hoover, LJ liquid: kT " << kt0 << " -> <kT> = " << m.mean << " +- " << m.error
            << " J over the second half (target 1; 10 blocks of " << kt.size() / 10
            << " steps); K + U + reservoir: max |change| " << worst << " J per atom, " << last
            << " at the end; reservoir " << NhReservoir(scene) / n << " J per atom\n";
  EXPECT_NEAR(kt0, 1.44, 1e-12);
  EXPECT_LT(std::abs(m.mean - 1.0), 3 * m.error);
  EXPECT_LT(m.error, 0.02);
  // Measured 1.4e-3 J per atom (largest while the crystal melts), about
  // what velocity Verlet's energy does at this step (lj_liquid_test: 1.2e-3).
  EXPECT_LT(worst, 4e-3);  // about 3x the measured value
}

// The cluster of verlet_reuse_test: 27 Lennard-Jones atoms and gravity,
// positions only. With a force that claims velocity dependence (Nothing)
// every step evaluates a0; the states are the same bits.
Scene NhCluster(const std::string& solver) { return test::LjCluster(solver); }

TEST(NoseHoover, OneForceEvaluationPerStepGivesTheSameBitsAsTwo) {
  const std::string solver = "{ type: nose_hoover, kT: 0.3, tdamp: 0.05 }";
  Scene once = NhCluster(solver), twice = NhCluster(solver);
  SystemAssembly(*twice.system).add_force(std::make_shared<test::Nothing>(), "nothing");
  test::StepThrough(once, 300, [](std::int64_t) {});
  test::StepThrough(twice, 300, [](std::int64_t) {});
  EXPECT_EQ(once.system->force_evaluations(), 301u);
  EXPECT_EQ(twice.system->force_evaluations(), 600u);
  EXPECT_TRUE(NhSameBits(once, twice));
  EXPECT_EQ(NhReservoir(once), NhReservoir(twice));
  EXPECT_NE(NhReservoir(once), 0.0);
}

// 17^3 = 4913 particles (more than kParallelMinElements, so 2 threads split
// the loops, and the fixed chunks of the 2K sum straddle the threads'
// ranges) on a lattice of undamped springs (positions only: the reuse path)
// or damped ones (velocities: the predictor path), with random velocities.
Eigen::VectorXd NhLatticeRun(int threads, const std::string& kd, double* reservoir) {
  set_threads(threads);
  Scene scene = test::load_text(
      "simulation: { dt: 0.002, steps: 1, solver: { type: nose_hoover, kT: 0.02, tdamp: 0.02 } }\n"
      "particles:\n"
      "  - lattice: { origin: [0, 0, 0], n: [17, 17, 17], spacing: 0.1, mass: 0.01, springs: { "
      "structural: { ks: 50, kd: " +
      kd + " } } }\n");
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal(0.0, 1.0);
  auto v = scene.system->velocities();
  for (Index i = 0; i < v.cols(); ++i) v.col(i) = Vec3(normal(rng), normal(rng), normal(rng));
  test::StepThrough(scene, 30, [](std::int64_t) {});
  EXPECT_EQ(max_threads(), threads);
  *reservoir = NhReservoir(scene);
  return scene.system->state();
}

TEST(NoseHoover, OneAndTwoThreadsGiveTheSameBits) {
  const int before = max_threads();
  for (const std::string kd : {"0", "0.001"}) {
    double r1 = 0.0, r2 = 0.0;
    const Eigen::VectorXd one = NhLatticeRun(1, kd, &r1);
    const Eigen::VectorXd two = NhLatticeRun(2, kd, &r2);
    EXPECT_TRUE(test::same_bits(one, two))
        << "kd " << kd << ": max |diff| " << (one - two).cwiseAbs().maxCoeff();
    EXPECT_EQ(r1, r2) << "kd " << kd;
    EXPECT_NE(r1, 0.0);
  }
  set_threads(before);
}

TEST(NoseHoover, AResumedRunIsTheSameBits) {
  const test::fs::path dir = test::temp_dir("nose-hoover-resume");
  std::string text =
      "simulation: { dt: 0.002, steps: 400, solver: { type: nose_hoover, kT: 0.3, tdamp: 0.05 "
      "} }\n"
      "output:\n"
      "  - { type: csv, path: out/frames.csv, every: 50 }\n"
      "  - { type: energy, path: out/energy.csv, every: 10, columns: [t, kinetic, potential, "
      "reservoir, conserved] }\n"
      "checkpoint: { path: out/run.ckpt }\n"
      "particles:\n";
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      for (int c = 0; c < 3; ++c)
        text += "  - { position: [" + std::to_string(1.12 * a) + ", " + std::to_string(1.12 * b) +
                ", " + std::to_string(1.12 * c + 0.05 * a) + "], mass: 1 }\n";
  text += "forces:\n  - { type: lennard_jones }\n";
  test::write_file(dir / "cluster.yaml", text);
  Checkpoint end, resumed;
  test::expect_resumed_run_is_whole_run(dir, "cluster.yaml", 173, end, resumed);
}

// The checkpoint bytes: what save_state() wrote restores bit for bit; bytes
// it could not have written are refused.
TEST(NoseHoover, TheCheckpointBytesAreChecked) {
  Scene a = NhCluster("{ type: nose_hoover, kT: 0.3, tdamp: 0.05, chain: 4 }");
  test::StepThrough(a, 50, [](std::int64_t) {});
  const std::vector<std::uint8_t> bytes = a.solver->save_state();
  EXPECT_EQ(bytes.size(), 12u + 8u + 16u * 4u);
  Scene b = NhCluster("{ type: nose_hoover, kT: 0.3, tdamp: 0.05, chain: 4 }");
  b.solver->restore_state(bytes);
  EXPECT_EQ(b.solver->save_state(), bytes);
  EXPECT_EQ(NhReservoir(a), NhReservoir(b));
  auto refused = [&](std::vector<std::uint8_t> bad) {
    try {
      b.solver->restore_state(bad);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  const std::string expected =
      "nose_hoover: the checkpoint's solver state is not one this nose_hoover (chain: 4) wrote (";
  EXPECT_EQ(refused({}).rfind(expected + "0 bytes; expected 84 bytes", 0), 0u) << refused({});
  std::vector<std::uint8_t> shorter(bytes.begin(), bytes.end() - 1);
  EXPECT_EQ(refused(shorter).rfind(expected + "83 bytes", 0), 0u) << refused(shorter);
  std::vector<std::uint8_t> magic = bytes;
  magic[0] = 'x';
  EXPECT_EQ(refused(magic).rfind(expected, 0), 0u);
  std::vector<std::uint8_t> nan = bytes;
  const double bad = std::nan("");
  std::memcpy(nan.data() + 20, &bad, 8);
  EXPECT_EQ(refused(nan).rfind(expected, 0), 0u);
  Scene three = NhCluster("{ type: nose_hoover, kT: 0.3, tdamp: 0.05 }");
  EXPECT_EQ(refused(three.solver->save_state()).rfind(expected + "68 bytes", 0), 0u);
  EXPECT_EQ(b.solver->save_state(), bytes);  // unchanged by what it refused
}

// Particles in the harmonic well U = |x|^2 / 2 (m = 1 and 2 kg), steps of dt.
Scene NhWell(const std::string& solver, int particles, double dt = 0.01) {
  std::string text = "simulation: { dt: " + test::Num(dt) + ", steps: 1, solver: " + solver +
                     " }\n"
                     "particles:\n"
                     "  - { position: [1, 0.5, -0.25], velocity: [0, 0.75, 0.5], mass: 1 }\n";
  if (particles > 1) text += "  - { position: [-1, 0, 0.5], velocity: [0.3, 0, 0], mass: 2 }\n";
  return test::load_text(text +
                         "forces:\n  - { type: field, force: ['-x', '-y', '-z'], potential: "
                         "'(x^2 + y^2 + z^2) / 2' }\n");
}

// One particle with the default extra_dof 3: N_f = 0, nothing to
// thermostat. The chain is inert and the run is verlet's, bit for bit, with
// one force evaluation per step; the reservoir is 0 at the start and stays 0.
TEST(NoseHoover, AnInertChainIsVerletAndItsReservoirStaysZero) {
  Scene nh = NhWell("{ type: nose_hoover, kT: 1, tdamp: 0.1 }", 1);
  Scene vv = NhWell("{ type: verlet }", 1);
  EXPECT_EQ(NhReservoir(nh), 0.0);
  test::StepThrough(nh, 500, [](std::int64_t) {});
  test::StepThrough(vv, 500, [](std::int64_t) {});
  EXPECT_TRUE(NhSameBits(nh, vv));
  EXPECT_EQ(NhReservoir(nh), 0.0);
  EXPECT_EQ(nh.system->force_evaluations(), 501u);
}

// Two particles with extra_dof 0 (N_f = 6), heated from K = 0.5 J towards
// N_f kT / 2 = 3 J over 20 s (40 tau): the reservoir starts at 0 and K + U +
// reservoir is conserved to O(h^2), the method's order.
TEST(NoseHoover, TheReservoirStartsAtZeroAndTheExtendedEnergyIsConservedToSecondOrder) {
  double worst[2] = {0.0, 0.0}, reservoir = 0.0;
  for (int k = 0; k < 2; ++k) {
    const double dt = 0.01 / (1 << k);
    Scene two = NhWell("{ type: nose_hoover, kT: 1, tdamp: 0.5, extra_dof: 0 }", 2, dt);
    const System& s = *two.system;
    EXPECT_EQ(NhReservoir(two), 0.0);
    const double e0 = s.kinetic_energy() + s.potential_energy();
    test::StepThrough(two, 2000 << k, [&](std::int64_t) {
      worst[k] = std::max(
          worst[k], std::abs(s.kinetic_energy() + s.potential_energy() + NhReservoir(two) - e0));
    });
    if (k == 0) reservoir = NhReservoir(two);
  }
  const double order = std::log2(worst[0] / worst[1]);
  std::cout << "nose_hoover, 2 particles in a well: max |K + U + reservoir - E0| = " << worst[0]
            << " J at dt 0.01, " << worst[1] << " J at dt 0.005 (order " << order << "); reservoir "
            << reservoir << " J at the end\n";
  EXPECT_LT(reservoir, -1.0);   // the chain gave the particles energy
  EXPECT_LT(worst[0], 1.5e-3);  // measured 5.4e-4 J: about 3x
  EXPECT_NEAR(order, 2.0, 0.3);
}

TEST(NoseHoover, EachBadValueGetsItsLocatedError) {
  auto with = [](const std::string& solver) {
    return test::load_problems("simulation: { dt: 0.01, steps: 1, solver: " + solver +
                               " }\n"
                               "particles:\n"
                               "  - { position: [0, 0, 0], mass: 1 }\n");
  };
  const std::string expected =
      "(expected temperature: T in K, or kT: k_B T in J for reduced units)";
  EXPECT_EQ(with("{ type: nose_hoover, tdamp: 0.5 }"),
            "test.yaml:1:43: simulation.solver.temperature: no temperature given " + expected);
  EXPECT_EQ(with("{ type: nose_hoover, kT: 1, temperature: 100, tdamp: 0.5 }"),
            "test.yaml:1:68: simulation.solver.kT: given with temperature (expected one of "
            "temperature: T in K, or kT: k_B T in J for reduced units)");
  EXPECT_EQ(with("{ type: nose_hoover, kT: 0, tdamp: 0.5 }"),
            "test.yaml:1:68: simulation.solver.kT: 0 is out of range (expected a number > 0 in J)");
  EXPECT_EQ(with("{ type: nose_hoover, temperature: -3, tdamp: 0.5 }"),
            "test.yaml:1:77: simulation.solver.temperature: -3 is out of range (expected a "
            "number > 0 in K)");
  EXPECT_EQ(with("{ type: nose_hoover, kT: 1, tdamp: 0 }"),
            "test.yaml:1:78: simulation.solver.tdamp: 0 is out of range (expected a number > 0 "
            "in s)");
  EXPECT_EQ(with("{ type: nose_hoover, kT: 1 }"),
            "test.yaml:1:43: simulation.solver: missing required key 'tdamp' (expected a number "
            "> 0 in s: damping time tau; LAMMPS suggests about 100 time steps)");
  for (const char* chain : {"0", "11"}) {
    EXPECT_EQ(with(std::string("{ type: nose_hoover, kT: 1, tdamp: 0.5, chain: ") + chain + " }"),
              std::string("test.yaml:1:90: simulation.solver.chain: ") + chain +
                  " is out of range (expected a whole number in [1, 10])");
  }
  EXPECT_EQ(with("{ type: nose_hoover, kT: 1, tdamp: 0.5, chain: 2.5 }"),
            "test.yaml:1:90: simulation.solver.chain: '2.5' is not a whole number (expected a "
            "whole number in [1, 10])");
  EXPECT_EQ(with("{ type: nose_hoover, kT: 1, tdamp: 0.5, extra_dof: -1 }"),
            "test.yaml:1:94: simulation.solver.extra_dof: -1 is out of range (expected a number "
            ">= 0)");
}

}  // namespace
}  // namespace pdyn
