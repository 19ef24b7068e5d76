// langevin's `generator: lammps` (plugins/forces/langevin/lammps_noise.hpp)
// and verlet's `velocity_forces: half_step`: LAMMPS's fix langevin numbers
// (RANMAR, the published test values), in the order of LAMMPS's atom sort,
// once per step boundary whatever the host evaluates, through a checkpoint;
// verlet's half-step scheme as LAMMPS's fix nve writes it. That a converted
// LAMMPS input follows LAMMPS's run is tests/cli/convert_test.cpp's.
#include <gtest/gtest.h>

#include <cmath>
#include <span>

#include "host/resume_support.hpp"
#include "pdyn/error.hpp"
#include "pdyn/host/assembly.hpp"
#include "pdyn/host/resolve.hpp"
#include "pdyn/plugin.hpp"
#include "pdyn/step_aware.hpp"
#include "pdyn/system.hpp"
#include "support/physics_support.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

const PluginDescriptor& langevin_plugin() {
  return *test::shipped_plugins().find(PluginKind::Force, "langevin")->descriptor;
}

// A langevin force on `sys` with generator lammps, kT 1, damp 1, the seed
// and the sort's bin.
std::unique_ptr<Force> lammps_langevin(const System& sys, long long seed, double bin) {
  Params given;
  given.set("kT", 1.0);
  given.set("damp", 1.0);
  given.set("seed", seed);
  given.set("generator", std::string("lammps"));
  given.set("lammps_sort_bin", bin);
  const Resolved r = resolve(langevin_plugin().params, given);
  EXPECT_TRUE(r.problems.empty());
  return langevin_plugin().create_force(r.params, SceneContext{sys.view(), nullptr});
}

// Particles of mass 1 at rest at `x` in the periodic box [0, 10)^3.
void place(System& sys, const Matrix3X& x) {
  SystemAssembly(sys).set_particles(
      x, Matrix3X::Zero(3, x.cols()), Eigen::VectorXd::Ones(x.cols()),
      std::vector<std::uint8_t>(static_cast<std::size_t>(x.cols()), 0));
  Domain box;
  box.max = Vec3::Constant(10.0);
  box.periodic = {true, true, true};
  SystemAssembly(sys).set_domain(box);
}

// With m = 1, damp = 1, kT = 1 and h = 24 the amplitude sqrt(24 m kT /
// (damp h)) is 1: a particle at rest gets u - 1/2 per component. The
// force of the evaluation at step boundary k.
Matrix3X noise_at(Force& f, System& sys, long long k) {
  const double h = 24.0;
  dynamic_cast<StepAware&>(f).begin_step(static_cast<double>(k) * h, h);
  sys.set_time(static_cast<double>(k) * h);
  Matrix3X out = Matrix3X::Zero(3, sys.size());
  f.add_forces(sys.view(), out);
  return out;
}

TEST(LangevinLammps, RanmarGivesThePublishedTestValues) {
  // Marsaglia, Zaman & Tsang (1990) with ij = 1802, kl = 9373 (LAMMPS's
  // seed 1802 * 30082 + 9373 + 1): after 20000 numbers the next six, times
  // 2^24, are 6533892, 14220222, 7275067, 6172232, 8354498, 10633180 (the
  // test of F. James, Comp. Phys. Comm. 60 (1990) 329). RanMars draws the
  // first number at construction, so they are draws 20000 to 20005 after it,
  // three per block for one particle: block 6666's y and z, 6667's, 6668's x.
  System sys;
  place(sys, Matrix3X::Constant(3, 1, 5.0));
  auto f = lammps_langevin(sys, 1802LL * 30082 + 9373 + 1, 0.0);
  std::vector<double> got;
  for (long long k = 6666; k <= 6668; ++k) {
    const Matrix3X w = noise_at(*f, sys, k);
    for (int d = 0; d < 3; ++d) got.push_back((w(d, 0) + 0.5) * 16777216.0);
  }
  const std::vector<double> published{6533892, 14220222, 7275067, 6172232, 8354498, 10633180};
  EXPECT_EQ(std::vector<double>(got.begin() + 1, got.begin() + 7), published);
}

TEST(LangevinLammps, TheNumbersGoInTheOrderOfLammpsAtomSort) {
  // Four particles; bins of 2.5 in the box of 10 (4 per axis, x fastest).
  // Particle 0 in bin (3, 0, 0) = 3, particle 1 in (0, 1, 0) = 4, particle 2
  // in (0, 0, 0) = 0 and particle 3 in (1, 0, 0) = 1 and wrapped from x =
  // 13.1 (LAMMPS sorts after its pbc()): sorted 2, 3, 0, 1.
  Matrix3X x(3, 4);
  x << 8.0, 0.5, 0.5, 13.1,  //
      0.5, 3.0, 0.5, 0.5,    //
      0.5, 0.5, 0.5, 0.5;
  System sys;
  place(sys, x);
  auto in_order = lammps_langevin(sys, 12345, 0.0);
  auto sorted = lammps_langevin(sys, 12345, 2.5);
  const Matrix3X a = noise_at(*in_order, sys, 0), b = noise_at(*sorted, sys, 0);
  EXPECT_EQ(b.col(2), a.col(0));
  EXPECT_EQ(b.col(3), a.col(1));
  EXPECT_EQ(b.col(0), a.col(2));
  EXPECT_EQ(b.col(1), a.col(3));
}

TEST(LangevinLammps, EachStepBoundaryHasItsNumbersHoweverOftenItIsEvaluated) {
  System sys;
  place(sys, Matrix3X::Constant(3, 2, 5.0));
  auto once = lammps_langevin(sys, 777, 0.0);
  auto often = lammps_langevin(sys, 777, 0.0);
  std::vector<Matrix3X> blocks;
  for (long long k = 0; k < 6; ++k) blocks.push_back(noise_at(*once, sys, k));
  // Again, again, a step back (a replayed step), a jump back to the start.
  EXPECT_EQ(noise_at(*often, sys, 0), blocks[0]);
  EXPECT_EQ(noise_at(*often, sys, 0), blocks[0]);
  EXPECT_EQ(noise_at(*often, sys, 1), blocks[1]);
  EXPECT_EQ(noise_at(*often, sys, 0), blocks[0]);
  EXPECT_EQ(noise_at(*often, sys, 4), blocks[4]);
  EXPECT_EQ(noise_at(*often, sys, 5), blocks[5]);
  EXPECT_EQ(noise_at(*often, sys, 2), blocks[2]);
  EXPECT_NE(blocks[1], blocks[0]);
  // A checkpoint's state continues the stream in another object.
  noise_at(*once, sys, 3);
  const std::vector<std::uint8_t> state = once->save_state();
  auto resumed = lammps_langevin(sys, 777, 0.0);
  resumed->restore_state(state);
  EXPECT_EQ(noise_at(*resumed, sys, 3), blocks[3]);
  EXPECT_EQ(noise_at(*resumed, sys, 4), blocks[4]);
  std::vector<std::uint8_t> damaged = state;
  damaged.resize(damaged.size() - 1);
  EXPECT_THROW(resumed->restore_state(damaged), Error);
  EXPECT_EQ(noise_at(*resumed, sys, 5), blocks[5]);  // a refused state changes nothing
}

TEST(LangevinLammps, AnEvaluationInsideAStepIsRefused) {
  System sys;
  place(sys, Matrix3X::Constant(3, 1, 5.0));
  auto f = lammps_langevin(sys, 5, 0.0);
  dynamic_cast<StepAware&>(*f).begin_step(0.0, 0.5);
  sys.set_time(0.25);
  Matrix3X out = Matrix3X::Zero(3, 1);
  try {
    f->add_forces(sys.view(), out);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(),
                 "langevin: generator lammps draws LAMMPS's numbers for evaluations at the ends "
                 "of steps, and this one is at t = 0.25 inside a step of 0.5 (expected solver "
                 "verlet or nose_hoover, which evaluate there)");
  }
}

TEST(LangevinLammps, BadValuesGetTheirLocatedErrors) {
  auto with = [](const std::string& force) {
    return test::load_problems(
        "simulation: { dt: 0.01, steps: 1, solver: { type: verlet } }\n"
        "particles:\n"
        "  - { position: [0, 0, 0], mass: 1 }\n"
        "forces:\n"
        "  - " +
        force + "\n");
  };
  EXPECT_EQ(with("{ type: langevin, kT: 1, damp: 1, generator: mt19937 }"),
            "test.yaml:5:50: forces[0].generator: 'mt19937' is not a generator (expected philox "
            "or lammps)");
  EXPECT_EQ(with("{ type: langevin, kT: 1, damp: 1, generator: lammps, seed: 0 }"),
            "test.yaml:5:64: forces[0].seed: 0 is outside LAMMPS's generator's seeds (expected 1 "
            "to 900000000)");
  EXPECT_EQ(with("{ type: langevin, kT: 1, damp: 1, lammps_sort_bin: 0.5 }"),
            "test.yaml:5:56: forces[0].lammps_sort_bin: is for generator lammps only (expected "
            "generator: lammps)");
  EXPECT_EQ(test::load_problems("simulation: { dt: 0.01, steps: 1, solver: { type: verlet, "
                                "velocity_forces: whole_step } }\n"
                                "particles:\n  - { position: [0, 0, 0], mass: 1 }\n"),
            "test.yaml:1:76: simulation.solver.velocity_forces: 'whole_step' is not a choice "
            "(expected predictor or half_step)");
}

// verlet with velocity_forces: half_step is LAMMPS's fix nve with the
// forces at v_half: v += h/2 a0, x += h v, a1 = a(x, v_half), v += h/2 a1,
// a1 kept as the next a0 (one evaluation per step). A damped spring, by hand
// and by the solver, agree to rounding; the predictor's run is another.
Vec3 DampedSpringByHand(int steps, double h, Vec3& v) {
  const double k = 4.0, c = 0.3;
  // The spring's force on particle 1, -(ks (|d| - r) + kd v.u) u.
  auto accel = [&](const Vec3& x, const Vec3& u_v) {
    const double len = x.norm();
    const Vec3 u = x / len;
    return Vec3(-(k * (len - 1.0) + c * u_v.dot(u)) * u);
  };
  Vec3 x(1.5, 0, 0);
  v = Vec3(0, 0.2, 0);
  Vec3 a = accel(x, v);
  for (int n = 0; n < steps; ++n) {
    v += (0.5 * h) * a;
    x += h * v;
    a = accel(x, v);
    v += (0.5 * h) * a;
  }
  return x;
}

TEST(LangevinLammps, HalfStepVerletIsLammpsScheme) {
  auto run = [](const std::string& how, Vec3& v) {
    Scene s = test::load_text(
        "simulation: { dt: 0.01, steps: 50, solver: { type: verlet, velocity_forces: " + how +
        " } }\n"
        "particles:\n"
        "  - { position: [0, 0, 0], mass: 1, fixed: true }\n"
        "  - { position: [1.5, 0, 0], velocity: [0, 0.2, 0], mass: 1 }\n"
        "forces:\n"
        "  - { type: spring, pairs: [[0, 1]], ks: 4, kd: 0.3, rest: 1 }\n");
    test::StepThrough(s, 50, [](std::int64_t) {});
    v = s.system->velocities().col(1);
    if (how == "half_step") {
      EXPECT_EQ(s.system->force_evaluations(), 51u);
    }
    return Vec3(s.system->positions().col(1));
  };
  Vec3 v_hand, v_half, v_predictor;
  const Vec3 x_hand = DampedSpringByHand(50, 0.01, v_hand);
  const Vec3 x_half = run("half_step", v_half);
  const Vec3 x_predictor = run("predictor", v_predictor);
  EXPECT_LT((x_half - x_hand).norm(), 1e-14);
  EXPECT_LT((v_half - v_hand).norm(), 1e-14);
  EXPECT_GT((x_predictor - x_hand).norm(), 1e-7);
}

TEST(LangevinLammps, AConvertedStyleRunResumesAsTheWholeRun) {
  // LAMMPS's 256-atom liquid in LAMMPS's bath and scheme, through a
  // checkpoint at step 37: the same frames, energies, state and generator
  // state as the run without a stop.
  const test::fs::path dir = test::temp_dir("langevin-lammps-resume");
  const std::string data = test::source_path("tests/scenes/thermo/thermo_start.data").string();
  test::write_file(dir / "liquid.yaml",
                   "simulation: { dt: 0.005, steps: 80, solver: { type: verlet, velocity_forces: "
                   "half_step }, box: { file: " +
                       data + " } }\nparticles:\n  - file: " + data +
                       "\nforces:\n  - { type: lennard_jones, cutoff: 2.5, shift: true }\n"
                       "  - { type: langevin, kT: 1, damp: 0.5, seed: 4242, generator: lammps, "
                       "lammps_sort_bin: 1.4 }\n"
                       "output:\n  - { type: csv, path: out/frames.csv, every: 20 }\n"
                       "  - { type: energy, path: out/energy.csv, every: 10 }\n"
                       "checkpoint: { path: out/run.ckpt }\n");
  Checkpoint whole, resumed;
  test::expect_resumed_run_is_whole_run(dir, "liquid.yaml", 37, whole, resumed);
}

}  // namespace
}  // namespace pdyn
