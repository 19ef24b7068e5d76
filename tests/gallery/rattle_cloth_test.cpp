// RATTLE (plugins/solvers/verlet/rattle.cpp) on the two cloths of issue 42
// item 5 (tests/scenes/rattle/): a 30 x 30 cloth of structural rods hung
// from one corner, which used to stop at step 843 to 2961 (a square of rods
// sheared flat, where RATTLE's position equations have no solution along
// J(x0)), and a 20 x 20 plate of structural, shear and bend rods pinned at
// two corners, which used to stop at step 1 (redundant rows: a singular
// J W J^T). Every rod keeps its length to 1e-10 m at every step. The suite
// runs the corner cloth past where it stopped and the plate for 0.1 s;
// ctest -L long (rattle_cloth.full.*) runs both for their whole 2 s. Then the
// multipliers of a redundant system (a triangle of rods and a duplicate of
// one) against the pseudo-inverse, and conflicting rows refused with their
// message, by RATTLE and by Witkin's constraint force.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cstdlib>
#include <iostream>

#include "gallery/gallery_support.hpp"
#include "host/resume_support.hpp"
#include "rattle.hpp"

namespace pdyn {
namespace rattle_cloth_test {

Scene LoadRattleScene(const std::string& name) {
  return load_scene(test::source_path("tests/scenes/rattle/" + name), test::shipped_plugins());
}

bool FullLength() { return std::getenv("PDYN_RATTLE_CLOTH_FULL") != nullptr; }

// Steps `scene` `steps` times; the largest |C| after any step.
double LargestErrorOver(Scene& scene, std::int64_t steps, const char* what) {
  System& sys = *scene.system;
  double worst = 0.0, lowest = sys.positions().row(2).minCoeff();
  test::StepThrough(scene, steps, [&](std::int64_t) {
    worst = std::max(worst, sys.constraint_error());
    lowest = std::min(lowest, sys.positions().row(2).minCoeff());
  });
  std::cout << what << ": " << steps << " steps of " << scene.dt << " s, max |C| = " << worst
            << " m, lowest z = " << lowest << " m\n";
  EXPECT_FALSE(sys.constraint_force_enabled());
  return worst;
}

TEST(RattleCloth, TheCornerHungClothKeepsEveryRodPastWhereItStopped) {
  Scene scene = LoadRattleScene("cloth_corner.yaml");
  ASSERT_EQ(scene.solver_name, "verlet");
  ASSERT_EQ(scene.system->constraint_rows(), 1740);
  ASSERT_EQ(scene.dt, 0.00025);
  EXPECT_LE(LargestErrorOver(scene, 1200, "corner cloth, 0.3 s"), 1e-10);
}

TEST(RattleCloth, ThePinnedPlateOfRedundantRodsKeepsEveryRod) {
  Scene scene = LoadRattleScene("cloth_plate.yaml");
  ASSERT_EQ(scene.system->constraint_rows(), 2202);
  const Matrix3X x0 = scene.system->positions();
  EXPECT_LE(LargestErrorOver(scene, 400, "plate, 0.1 s"), 1e-10);
  // It hangs still: gravity lies in its plane, which the rods make rigid.
  EXPECT_LE((scene.system->positions() - x0).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(GalleryRattleCloth, TheCornerHungClothForTwoSeconds) {
  if (!FullLength()) GTEST_SKIP() << "the whole 2 s: ctest -L long (rattle_cloth.full.*)";
  Scene scene = LoadRattleScene("cloth_corner.yaml");
  EXPECT_LE(LargestErrorOver(scene, scene.steps, "corner cloth, 2 s"), 1e-10);
}

TEST(GalleryRattleCloth, ThePinnedPlateForTwoSeconds) {
  if (!FullLength()) GTEST_SKIP() << "the whole 2 s: ctest -L long (rattle_cloth.full.*)";
  Scene scene = LoadRattleScene("cloth_plate.yaml");
  EXPECT_LE(LargestErrorOver(scene, scene.steps, "plate, 2 s"), 1e-10);
}

// Rods ab, bc, ca of an equilateral triangle of unit masses and a second
// rod ab: J W J^T is singular, its null space (1, 0, 0, -1). The velocity
// stage's multipliers solve J W J^T mu = J v; the minimum-norm ones are
// the pseudo-inverse's (Eigen's complete orthogonal decomposition of the
// dense matrix) and split the triangle's ab multiplier equally.
TEST(ConstraintSolves, ATriangleWithADuplicateRodGetsTheMinimumNormMultipliers) {
  Scene scene = load_scene_text(R"(
simulation: { dt: 0.001, steps: 1, solver: { type: verlet } }
particles:
  - { position: [0, 0, 0], velocity: [0.3, -0.2, 0.1], mass: 1 }
  - { position: [1, 0, 0], velocity: [-0.5, 0.4, 0], mass: 1 }
  - { position: [0.5, 0.8660254037844386, 0], velocity: [0.1, 0.7, -0.2], mass: 1 }
constraints:
  - { type: distance, pairs: [[0, 1], [1, 2], [2, 0]] }
  - { type: distance, pairs: [[0, 1]] }
)",
                                "triangle.yaml", test::shipped_plugins());
  System& sys = *scene.system;
  const ConstraintRows& rows = sys.evaluate_constraint_rows();
  ASSERT_EQ(rows.rows(), 4);
  Eigen::MatrixXd j = Eigen::MatrixXd::Zero(4, 9);
  for (Index r = 0; r < 4; ++r) {
    for (Index e = rows.row_begin[r]; e < rows.row_begin[r + 1]; ++e)
      j.block<1, 3>(r, 3 * rows.particle[e]) = rows.jacobian.col(e).transpose();
  }
  const Eigen::VectorXd v = Eigen::Map<const Eigen::VectorXd>(sys.velocities().data(), 9);
  const Eigen::MatrixXd a = j * j.transpose();  // W = I
  const Eigen::VectorXd b = j * v;
  const Eigen::VectorXd reference = a.completeOrthogonalDecomposition().solve(b);
  const Eigen::Matrix3d a3 = a.topLeftCorner<3, 3>();
  const Eigen::Vector3d triangle = a3.ldlt().solve(b.head<3>());

  pdyn_verlet::Rattle rattle(1e-12, 100);
  rattle.begin(sys);
  rattle.project_velocities(sys);
  const Eigen::VectorXd& mu = rattle.multipliers();
  std::cout << "triangle + duplicate: mu = " << mu.transpose()
            << ", pseudo-inverse: " << reference.transpose() << "\n";
  EXPECT_LE((mu - reference).norm(), 1e-12 * reference.norm());
  EXPECT_NEAR(mu(0), 0.5 * triangle(0), 1e-12);
  EXPECT_NEAR(mu(3), 0.5 * triangle(0), 1e-12);
  EXPECT_NEAR(mu(1), triangle(1), 1e-12);
  EXPECT_NEAR(mu(2), triangle(2), 1e-12);
  // and the velocities keep every rod's length: J v = 0
  const Eigen::VectorXd v1 = Eigen::Map<const Eigen::VectorXd>(sys.velocities().data(), 9);
  EXPECT_LE((j * v1).cwiseAbs().maxCoeff(), 1e-12);
}

// One particle pinned to two points: no motion keeps both.
std::string ConflictMessage(const std::string& solver) {
  Scene scene = load_scene_text(R"(
simulation:
  dt: 0.001
  steps: 10
  solver: { type: )" + solver + R"( }
  constraint_force: { ks: 100 }
particles:
  - { position: [0, 0, 0], mass: 1 }
constraints:
  - { type: pin, ids: [0] }
  - { type: pin, ids: [0], points: [[0.1, 0, 0]] }
forces:
  - { type: gravity, g: [0, 0, -9.81] }
)",
                                "conflict.yaml", test::shipped_plugins());
  Stepper stepper(*scene.system, *scene.solver, scene.solver_label);
  EXPECT_FALSE(stepper.step_to(scene.dt).has_value());
  return stepper.fault().what;
}

TEST(ConstraintSolves, ConflictingRowsAreRefusedWithTheirMessage) {
  const std::string rattle = ConflictMessage("verlet");
  EXPECT_NE(rattle.find("verlet (RATTLE): a constraint is still off by"), std::string::npos)
      << rattle;
  EXPECT_NE(rattle.find("or are two constraints in conflict?)"), std::string::npos) << rattle;
  const std::string force = ConflictMessage("rk4");
  EXPECT_NE(force.find("constraints: the constraint force's conjugate gradients stopped after"),
            std::string::npos)
      << force;
  EXPECT_NE(force.find("are two constraints in conflict, e.g. a particle pinned to two points?)"),
            std::string::npos)
      << force;
}

// Witkin's constraint force on the corner cloth (rk4): its solve carries
// nothing between evaluations (the factor is made afresh at each), so a run
// split by a checkpoint and resumed writes the uninterrupted run's bits.
TEST(ConstraintSolves, WitkinsForceOnTheClothResumesBitIdentically) {
  namespace fs = std::filesystem;
  const fs::path dir = test::temp_dir("witkin-cloth-resume");
  fs::copy_file(test::source_path("tests/scenes/rattle/cloth_corner.yaml"), dir / "scene.yaml",
                fs::copy_options::overwrite_existing);
  auto run = [&](const std::string& steps, std::vector<std::string> more) {
    std::vector<std::string> args = {"run",
                                     "scene.yaml",
                                     "--steps",
                                     steps,
                                     "-q",
                                     "--set",
                                     "simulation.solver={type: rk4}",
                                     "--set",
                                     "output.every=5",
                                     "--set",
                                     "output.checkpoint={path: out/split.ckpt}"};
    args.insert(args.end(), more.begin(), more.end());
    return test::pdyn_in(dir, args);
  };
  auto whole = run("40", {});
  ASSERT_EQ(whole.status, 0) << whole.err;
  fs::create_directories(dir / "ref");
  for (const char* f : {"cloth_corner.csv", "split.ckpt"})
    fs::rename(dir / "out" / f, dir / "ref" / f);
  auto first = run("20", {});
  ASSERT_EQ(first.status, 0) << first.err;
  auto rest = run("40", {"--resume", "out/split.ckpt"});
  ASSERT_EQ(rest.status, 0) << rest.err;
  for (const char* f : {"cloth_corner.csv", "split.ckpt"}) {
    EXPECT_EQ(test::read_bytes(dir / "ref" / f), test::read_bytes(dir / "out" / f)) << f;
  }
}

}  // namespace rattle_cloth_test
}  // namespace pdyn
