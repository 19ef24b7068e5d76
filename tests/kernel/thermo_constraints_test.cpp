// Temperature and pressure with constraints (pdyn/thermo.hpp; docs/
// constraints.md, "Temperature and pressure"), against numbers worked by
// hand: each independent constraint row removes one degree of freedom,
// redundant rows once (constraint_dof, dense and sparse QR); a rod's
// constraint force adds Lambda times its length to the virial, with
// Lambda Witkin's multiplier (the centripetal tension -2 m u^2 / d of a
// spinning dimer, whose pressure is then exactly 0) or RATTLE's position
// stage of the step starting at the state (the same tension over a step of
// h: Lambda = (sqrt(d^2 - 4 u^2 h^2) - d) m / h^2); the energy writer's dof,
// kT, virial and pressure columns show them.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "host/resume_support.hpp"
#include "pdyn/system.hpp"
#include "pdyn/thermo.hpp"
#include "support/lammps_thermo.hpp"
#include "support/physics_support.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace constrained_thermo {  // named: the tests' unity build shares translation units

namespace fs = std::filesystem;

constexpr double kMass = 2.0, kSpeed = 0.3, kLength = 1.0, kStep = 0.01;

// Two particles of kMass, kLength apart along x in a periodic 10 m box, the
// rod between them spinning about z: velocities +-kSpeed along y. `how` is
// verlet's `constraints:` (rattle or force).
std::string spinning_dimer(const std::string& how, const std::string& output = "") {
  return "simulation: { dt: 0.01, steps: 1, solver: { type: verlet, constraints: " + how +
         " }, box: { min: [0, 0, 0], max: [10, 10, 10], periodic: [true, true, true] } }\n"
         "particles:\n"
         "  - { position: [9.75, 5, 5], velocity: [0, 0.3, 0], mass: 2 }\n"
         "  - { position: [0.75, 5, 5], velocity: [0, -0.3, 0], mass: 2 }\n"
         "constraints:\n"
         "  - { type: distance, pairs: [[0, 1]] }\n" +
         output;
}

TEST(ThermoConstraints, ARigidDimerHasTwoDegreesOfFreedom) {
  // 3 N - 3 - 1 = 2: the rod's two rotations (the momentum is removed).
  Scene scene = test::load_text(spinning_dimer("rattle"));
  EXPECT_EQ(constraint_dof(*scene.system), 1.0);
  const Thermo th = thermo(scene.system->view(), 0.0, 3.0 + constraint_dof(*scene.system));
  EXPECT_EQ(th.dof, 2.0);
  EXPECT_NEAR(th.kT, kMass * kSpeed * kSpeed, 1e-16);  // K = m u^2, kT = 2 K / 2
}

TEST(ThermoConstraints, WitkinsRodTensionBalancesTheKineticPressureOfASpinningDimer) {
  // The rod, across the periodic face x = 0, holds the two ends on their
  // circle: Lambda = -2 m u^2 / d (a tension), W = Lambda d = -2 K, so that
  // P = (2 K + W) / (3 V) = 0: a lone spinning molecule exerts no pressure.
  Scene scene = test::load_text(spinning_dimer("force"));
  System& sys = *scene.system;
  sys.compute_accelerations();
  const VirialSum w = total_virial(sys, scene.solver.get(), scene.dt);
  const double expected = -2.0 * kMass * kSpeed * kSpeed;
  EXPECT_EQ(w.missing, "");
  EXPECT_NEAR(w.value, expected, 1e-15);
  EXPECT_NEAR(sys.constraint_force_virial(), expected, 1e-15);
  const Thermo th = thermo(sys.view(), w.value, 3.0 + constraint_dof(sys));
  EXPECT_NEAR(th.pressure, 0.0, 1e-17);
  std::cout << "thermo constraints: Witkin's rod virial " << w.value << " J (by hand " << expected
            << "), pressure " << th.pressure << " Pa\n";
}

TEST(ThermoConstraints, RattlesRodVirialIsItsPositionStagesTensionTimesTheLength) {
  // The drift of a step of h moves the ends apart to a separation (d, 2 u h);
  // RATTLE's position stage pulls them back along the rod at the start,
  // (d + h^2 (2/m) Lambda)^2 + (2 u h)^2 = d^2 (m/2 the reduced mass), so
  // Lambda = (sqrt(d^2 - 4 u^2 h^2) - d) m / (2 h^2) ... times 2 for the two
  // ends' share: Lambda = m (sqrt(d^2 - 4 u^2 h^2) - d) / h^2, and W =
  // Lambda d, which tends to Witkin's -2 m u^2 as h -> 0.
  Scene scene = test::load_text(spinning_dimer("rattle"));
  System& sys = *scene.system;
  sys.compute_accelerations();
  const VirialSum w = total_virial(sys, scene.solver.get(), kStep);
  const double a = 4.0 * kSpeed * kSpeed * kStep * kStep;
  const double lambda = kMass * (-a / (std::sqrt(kLength * kLength - a) + kLength)) /
                        (kStep * kStep);  // sqrt(d^2 - a) - d without cancellation
  const double expected = lambda * kLength;
  EXPECT_EQ(w.missing, "");
  // To rounding: positions near 10 m carry 1.8e-15 m, which the stage's
  // Lambda magnifies by m / h^2 = 2e4 (8.7e-11 relative measured).
  EXPECT_NEAR(w.value, expected, 1e-9 * std::abs(expected));
  EXPECT_NEAR(w.value, -2.0 * kMass * kSpeed * kSpeed, 1e-4);  // O(u^2 h^2 / d^2) from Witkin's
  std::cout << "thermo constraints: RATTLE's rod virial " << test::Num(w.value) << " J (by hand "
            << test::Num(expected) << ")\n";
}

TEST(ThermoConstraints, TheEnergyWritersColumnsCountTheRodAndItsVirial) {
  const fs::path dir = test::temp_dir("thermo-constraints-writer");
  for (const std::string how : {"rattle", "force"}) {
    test::write_file(dir / "s.yaml",
                     spinning_dimer(how,
                                    "output:\n  - { type: energy, path: e.csv, every: 1, columns: "
                                    "[step, dof, kT, virial, pressure] }\n"));
    const auto r = test::pdyn_in(dir, {"run", "s.yaml", "-q"});
    ASSERT_EQ(r.status, 0) << r.err;
    const auto lines = test::split_lines(test::read_bytes(dir / "e.csv"));
    ASSERT_GE(lines.size(), 2u);
    EXPECT_EQ(lines[0], "step,dof,kT,virial,pressure");
    std::stringstream row(lines[1]);
    std::vector<double> v;
    for (std::string cell; std::getline(row, cell, ',');) v.push_back(std::stod(cell));
    ASSERT_EQ(v.size(), 5u);
    EXPECT_EQ(v[1], 2.0) << how;
    EXPECT_NEAR(v[2], kMass * kSpeed * kSpeed, 1e-15) << how;
    EXPECT_NEAR(v[3], -2.0 * kMass * kSpeed * kSpeed, how == "force" ? 1e-15 : 1e-4) << how;
    EXPECT_NEAR(v[4], 0.0, how == "force" ? 1e-17 : 1e-7) << how;
  }
}

TEST(ThermoConstraints, TheDimerLiquidsTemperatureAndPressureAgreeWithLammps) {
  // tests/scenes/dimers: 256 rigid Lennard-Jones dimers, LAMMPS's fix
  // rattle state at step 0 continued by verlet's RATTLE; LAMMPS's temp and
  // press at steps 0, 100 and 200 (reference.thermo, written by
  // bench/dimers_vs_lammps.sh --write-reference) against pdyn's kT and
  // pressure. Without the constraints' degrees of freedom kT was 17 % low
  // (3 N - 3 = 1533 against 1277), without their virial the pressure was off
  // by several times.
  // Every column to 1e-8 relative, the pressure too (no ideal-gas floor).
  auto ours = test::expect_lammps_thermo("dimers", {"dimers.yaml", "dimers_start.data"},
                                         "out/dimers-energy.csv", 1e-8, 0.0);
  EXPECT_EQ(ours["step"], (std::vector<double>{0, 100, 200}));
  for (const double dof : ours["dof"]) EXPECT_EQ(dof, 3.0 * 512 - 3 - 256);
}

TEST(ThermoConstraints, ANoseHooverChainHoldsTheDimerLiquidAtItsKtCountedWithTheRods) {
  // The chain drives 2 K towards N_f kT (dxi_1/dt = (2 K - N_f kT) / Q_1),
  // so over a run <2 K> / N_f is its kT only if the chain's N_f is the
  // writer's, 3 N - 3 - 256 = 1277. With 3 N - 3 = 1533 the writer's kT would
  // settle 1533 / 1277 = 1.20 times too hot.
  const fs::path dir = test::temp_dir("thermo-dimers-nh");
  fs::copy_file(test::source_path("tests/scenes/dimers/dimers.yaml"), dir / "dimers.yaml");
  fs::copy_file(test::source_path("tests/scenes/dimers/dimers_start.data"),
                dir / "dimers_start.data");
  const auto run = test::pdyn_in(
      dir, {"run", "dimers.yaml", "-q", "--set", "simulation.steps=3000", "--set",
            "simulation.solver={ type: nose_hoover, kT: 1.0, tdamp: 0.25 }", "--set",
            "output=[{ type: energy, path: e.csv, every: 10, columns: [step, kT, dof] }]"});
  ASSERT_EQ(run.status, 0) << run.err;
  auto e = test::csv_columns(dir / "e.csv");
  double sum = 0.0;
  int n = 0;
  for (std::size_t k = 0; k < e["step"].size(); ++k) {
    EXPECT_EQ(e["dof"][k], 1277.0);
    if (e["step"][k] < 1000) continue;
    sum += e["kT"][k];
    ++n;
  }
  const double mean = sum / n;
  EXPECT_NEAR(mean, 1.0, 0.03);
  std::cout << "thermo constraints: Nose-Hoover at kT 1 on the dimers: mean kT " << mean
            << " over steps 1000-3000\n";
}

TEST(ThermoConstraints, RedundantRowsCountOnce) {
  // A rigid triangle of rods, one rod given twice (two distance entries): 4
  // rows of rank 3, N_f = 9 - 3 - 3 = 3 (its rotations).
  Scene triangle = test::load_text(
      "simulation: { dt: 0.01, steps: 1 }\n"
      "particles:\n"
      "  - { position: [0, 0, 0], mass: 1 }\n"
      "  - { position: [1, 0, 0], mass: 1 }\n"
      "  - { position: [0.3, 0.8, 0.1], mass: 1 }\n"
      "constraints:\n"
      "  - { type: distance, pairs: [[0, 1], [1, 2], [2, 0]] }\n"
      "  - { type: distance, pairs: [[1, 0]] }\n");
  EXPECT_EQ(triangle.system->constraint_rows(), 4);
  EXPECT_EQ(constraint_dof(*triangle.system), 3.0);
  // Two corners nailed: the rod between them acts on nothing; the other two
  // leave the third corner its circle about the axis: 3 - 2 = 1.
  Scene hinged = test::load_text(
      "simulation: { dt: 0.01, steps: 1 }\n"
      "particles:\n"
      "  - { position: [0, 0, 0], mass: 1, fixed: true }\n"
      "  - { position: [1, 0, 0], mass: 1, fixed: true }\n"
      "  - { position: [0.3, 0.8, 0.1], mass: 1 }\n"
      "constraints:\n"
      "  - { type: distance, pairs: [[0, 1], [1, 2], [2, 0]] }\n");
  EXPECT_EQ(constraint_dof(*hinged.system), 2.0);
  EXPECT_EQ(thermo(hinged.system->view(), 0.0, constraint_dof(*hinged.system)).dof, 1.0);
  // A pin's three rows on a particle that a rod also ties to a nailed one:
  // the rod adds nothing (rank 3 of 4 rows).
  Scene pinned = test::load_text(
      "simulation: { dt: 0.01, steps: 1 }\n"
      "particles:\n"
      "  - { position: [0, 0, 0], mass: 1, fixed: true }\n"
      "  - { position: [1, 0.5, 0], mass: 1 }\n"
      "constraints:\n"
      "  - { type: pin, ids: [1] }\n"
      "  - { type: distance, pairs: [[0, 1]] }\n");
  EXPECT_EQ(constraint_dof(*pinned.system), 3.0);
}

TEST(ThermoConstraints, ALongChainGivenTwiceCountsItsRodsOnceBySparseQr) {
  // 301 particles, 300 rods, every rod given twice: one group of 600 rows,
  // above the dense QR's 200, of rank 300.
  std::string pairs;
  for (int k = 0; k < 300; ++k)
    pairs += (k ? ", [" : "[") + std::to_string(k) + ", " + std::to_string(k + 1) + "]";
  std::string yaml =
      "simulation: { dt: 0.01, steps: 1 }\n"
      "particles:\n"
      "  - chain: { from: [0, 0, 0], to: [30, 0, 3], n: 301, mass: 0.1 }\n"
      "constraints:\n"
      "  - { type: distance, pairs: [" +
      pairs +
      "] }\n"
      "  - { type: distance, pairs: [" +
      pairs + "] }\n";
  Scene chain = test::load_text(yaml);
  EXPECT_EQ(chain.system->constraint_rows(), 600);
  EXPECT_EQ(constraint_dof(*chain.system), 300.0);
}

// The rank constraint_dof is the count of: J restricted to the free
// particles' coordinates, each row scaled to unit length, by dense
// column-pivoted QR of J^T with the threshold 1e-10 (the method of its
// groups up to 200 rows).
double DenseConstraintRank(const System& sys) {
  const ConstraintRows& rows = sys.evaluate_constraint_rows();
  const auto& fixed = sys.fixed();
  Eigen::MatrixXd jt = Eigen::MatrixXd::Zero(3 * sys.size(), rows.rows());
  for (Index r = 0; r < rows.rows(); ++r) {
    for (Index e = rows.row_begin[r]; e < rows.row_begin[r + 1]; ++e) {
      if (fixed[static_cast<std::size_t>(rows.particle[e])] != 0) continue;
      jt.block<3, 1>(3 * rows.particle[e], r) += rows.jacobian.col(e);
    }
    if (jt.col(r).norm() > 0.0) jt.col(r).normalize();
  }
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(jt);
  qr.setThreshold(1e-10);
  return static_cast<double>(qr.rank());
}

// An n x n sheet of particles, (i, j) at `at(i, j)`, with rods to their
// neighbours along the rows and columns, across the diagonals and to the
// second neighbours (a cloth's structural, shear and bend rods), each given
// `copies` times; the particles of `fixed` are nailed. The positions are
// written to the last bit.
std::string RodSheet(int n, const std::function<Vec3(int, int)>& at, const std::vector<int>& fixed,
                     int copies = 1) {
  std::string yaml = "simulation: { dt: 0.01, steps: 1 }\nparticles:\n";
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const bool nailed = std::find(fixed.begin(), fixed.end(), j * n + i) != fixed.end();
      const Vec3 x = at(i, j);
      yaml += fmt::format("  - {{ position: [{}, {}, {}], mass: 1{} }}\n", x.x(), x.y(), x.z(),
                          nailed ? ", fixed: true" : "");
    }
  }
  std::string pairs;
  auto rod = [&](int i, int j, int di, int dj) {
    if (i + di < 0 || i + di >= n || j + dj >= n) return;
    pairs += fmt::format("{}[{}, {}]", pairs.empty() ? "" : ", ", j * n + i, (j + dj) * n + i + di);
  };
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      for (const auto& [di, dj] : {std::pair{1, 0}, {0, 1}, {1, 1}, {-1, 1}, {2, 0}, {0, 2}}) {
        rod(i, j, di, dj);
      }
    }
  }
  yaml += "constraints:\n";
  for (int c = 0; c < copies; ++c) yaml += "  - { type: distance, pairs: [" + pairs + "] }\n";
  return yaml;
}

TEST(ThermoConstraints, AClothsRankIsTheDenseQrs) {
  // 12 x 12 particles, 746 rods: one group above the dense QR's 200 rows,
  // ranked by Givens rotations (thermo.cpp, sparse_rank). Flat, its rods
  // leave every particle its motion across the plane and make the sheet
  // rigid in it: 2 N - 3 rows count, 2 N - 1 with a corner nailed (the
  // rotation about it is left), 2 N - 4 with two (the rod between them
  // counts none). In a plane along no axis the rows' components across it
  // are rounding, not 0, and still count none. Crumpled, most rows count;
  // every rod given twice, none more.
  const auto flat = [](int i, int j) { return Vec3(0.1 * i, 0.1 * j, 0.0); };
  const auto tilted = [](int i, int j) {
    return Vec3(0.1 * i + 0.03 * j, 0.07 * j - 0.02 * i, 0.05 * j + 0.011 * i);
  };
  const auto crumpled = [](int i, int j) {
    return Vec3(0.1 * i, 0.1 * j, 0.03 * std::sin(1.3 * i) * std::cos(0.7 * j));
  };
  struct Case {
    std::string what;
    std::string yaml;
    double expected;  // -1: the dense QR's only
  };
  const std::vector<Case> cases = {
      {"flat", RodSheet(12, flat, {}), 2.0 * 144 - 3},
      {"flat, a corner nailed", RodSheet(12, flat, {0}), 2.0 * 143 - 1},
      {"flat, two corners nailed", RodSheet(12, flat, {132, 143}), 2.0 * 142},
      {"flat, every rod twice", RodSheet(12, flat, {}, 2), 2.0 * 144 - 3},
      {"tilted, a corner nailed", RodSheet(12, tilted, {0}), 2.0 * 143 - 1},
      {"crumpled", RodSheet(12, crumpled, {}), -1},
      {"crumpled, a corner nailed, every rod twice", RodSheet(12, crumpled, {0}, 2), -1}};
  for (const Case& c : cases) {
    Scene scene = test::load_text(c.yaml);
    const double dense = DenseConstraintRank(*scene.system);
    EXPECT_EQ(constraint_dof(*scene.system), dense) << c.what;
    if (c.expected >= 0) {
      EXPECT_EQ(dense, c.expected) << c.what;
    }
    std::cout << "thermo constraints: " << c.what << ": " << scene.system->constraint_rows()
              << " rows of rank " << dense << "\n";
  }
}

}  // namespace constrained_thermo
}  // namespace pdyn
