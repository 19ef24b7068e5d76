// nose_hoover's barostat (`pressure:`, the isotropic MTK barostat of
// LAMMPS's fix npt iso; its comparison with LAMMPS step for step is
// tests/cli/convert_test.cpp's MeltUnderNptFollowsLammps). Here: LAMMPS's
// 256-atom Lennard-Jones liquid holds the target pressure and temperature
// within their statistical errors and conserves K + U + reservoir (which
// now holds P0 (V - V0) and the barostat's energies); the conserved
// quantity's error is second order in the step; a resumed run is the same
// bits, the box included; 1 and 2 threads give the same bits; each bad
// set-up is refused with its message.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "host/resume_support.hpp"
#include "pdyn/host/threads.hpp"
#include "pdyn/system.hpp"
#include "pdyn/thermo.hpp"
#include "support/physics_support.hpp"
#include "support/statistics.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

double Volume(const System& s) {
  const Domain& d = s.domain();
  return (d.max[0] - d.min[0]) * (d.max[1] - d.min[1]) * (d.max[2] - d.min[2]);
}

double Conserved(const Scene& scene) {
  const System& s = *scene.system;
  return s.kinetic_energy() + s.potential_energy() + total_reservoir_energy(s, scene.solver.get());
}

TEST(NoseHooverBarostat, ALiquidHoldsThePressureAndConservesTheExtendedEnergy) {
  // tdamp 100 steps, pdamp 1000 steps, as LAMMPS suggests; 8000 steps.
  Scene scene =
      test::LjLiquid("{ type: nose_hoover, kT: 1, tdamp: 0.5, pressure: 1, pdamp: 5 }", "", true);
  const System& s = *scene.system;
  const double n = static_cast<double>(s.size());
  const double v0 = Volume(s), h0 = Conserved(scene);
  EXPECT_EQ(total_reservoir_energy(s, scene.solver.get()), 0.0);
  std::vector<double> p, kt, volume;
  double worst = 0.0;
  const std::int64_t steps = 8000;
  test::StepThrough(scene, steps, [&](std::int64_t k) {
    if (k > steps / 2) {
      const Thermo t = thermo(s.view(), total_virial(s).value);
      p.push_back(t.pressure);
      kt.push_back(t.kT);
      volume.push_back(t.volume);
    }
    if (k % 10 == 0) worst = std::max(worst, std::abs(Conserved(scene) - h0) / n);
  });
  const test::MeanError mp = test::block_average(p, 8), mt = test::block_average(kt, 8),
                        mv = test::block_average(volume, 8);
  std::cout << "nose_hoover barostat, LJ liquid (P0 1, kT 1): <P> = " << mp.mean << " +- "
            << mp.error << ", <kT> = " << mt.mean << " +- " << mt.error << ", <V> = " << mv.mean
            << " +- " << mv.error << " (from " << v0 << "); K + U + reservoir: max |change| "
            << worst << " J per atom\n";
  EXPECT_LT(std::abs(mp.mean - 1.0), 3 * mp.error);
  EXPECT_LT(mp.error, 0.1);
  EXPECT_LT(std::abs(mt.mean - 1.0), 3 * mt.error);
  EXPECT_GT(std::abs(mv.mean - v0), 3 * mv.error);  // the box did move
  EXPECT_LT(worst, 5e-3);
}

// The conserved quantity's largest error over 0.5 s falls by 2^2 when the
// step is halved: the splitting is second order.
TEST(NoseHooverBarostat, TheExtendedEnergyIsConservedToSecondOrder) {
  std::vector<double> error;
  for (const double dt : {0.004, 0.002, 0.001}) {
    Scene scene = test::LjLiquid(
        "{ type: nose_hoover, kT: 1.5, tdamp: 0.1, pressure: 3, pdamp: 0.5 }", "", true);
    scene.dt = dt;
    const double h0 = Conserved(scene);
    double worst = 0.0;
    test::StepThrough(scene, static_cast<std::int64_t>(std::lround(0.5 / dt)), [&](std::int64_t) {
      worst = std::max(worst, std::abs(Conserved(scene) - h0));
    });
    error.push_back(worst);
  }
  const double order1 = std::log2(error[0] / error[1]), order2 = std::log2(error[1] / error[2]);
  std::cout << "nose_hoover barostat: max |dH| " << error[0] << ", " << error[1] << ", " << error[2]
            << " J at dt 0.004, 0.002, 0.001: orders " << order1 << ", " << order2 << "\n";
  EXPECT_NEAR(order1, 2.0, 0.3);
  EXPECT_NEAR(order2, 2.0, 0.3);
}

std::string BoxScene() {
  const std::string data = test::source_path("tests/scenes/thermo/thermo_start.data").string();
  return "simulation: { dt: 0.005, steps: 300, solver: { type: nose_hoover, kT: 1.2, tdamp: 0.5, "
         "pressure: 2, pdamp: 2 }, box: { file: " +
         data + " } }\nparticles:\n  - file: " + data +
         "\nforces:\n  - { type: lennard_jones, cutoff: 2.5, shift: true }\n"
         "output:\n  - { type: csv, path: out/frames.csv, every: 50 }\n"
         "  - { type: energy, path: out/energy.csv, every: 10, columns: [step, kT, pressure, "
         "volume, reservoir, conserved] }\ncheckpoint: { path: out/run.ckpt }\n";
}

TEST(NoseHooverBarostat, AResumedRunIsTheSameBitsTheBoxIncluded) {
  const test::fs::path dir = test::temp_dir("barostat-resume");
  test::write_file(dir / "npt.yaml", BoxScene());
  Checkpoint end, resumed;
  ASSERT_NO_FATAL_FAILURE(
      test::expect_resumed_run_is_whole_run(dir, "npt.yaml", 173, end, resumed));
  ASSERT_TRUE(end.box.has_value());
  ASSERT_TRUE(resumed.box.has_value());
  EXPECT_EQ(end.box->min, resumed.box->min);
  EXPECT_EQ(end.box->max, resumed.box->max);
  // The volume column moved: the box in the frames is the barostat's.
  const auto columns = test::csv_columns(dir / "out/energy.csv");
  EXPECT_NE(columns.at("volume").front(), columns.at("volume").back());
}

TEST(NoseHooverBarostat, OneAndTwoThreadsGiveTheSameBits) {
  std::vector<Eigen::VectorXd> states;
  for (const int threads : {1, 2}) {
    set_threads(threads);
    Scene scene = test::load_text(BoxScene(), {{"output", "~"}, {"checkpoint", "~"}});
    test::StepThrough(scene, 100, [](std::int64_t) {});
    states.push_back(scene.system->state());
  }
  set_threads(0);
  EXPECT_TRUE(test::same_bits(states[0], states[1]));
}

TEST(NoseHooverBarostat, EachBadSetUpIsRefused) {
  EXPECT_EQ(test::load_problems("simulation: { dt: 0.005, steps: 1, solver: { type: nose_hoover, "
                                "kT: 1, tdamp: 0.5, pressure: 1 } }\nparticles:\n  - { position: "
                                "[0, 0, 0], mass: 1 }\n"),
            "test.yaml:1:44: simulation.solver.pdamp: the barostat needs both pressure and pdamp "
            "(expected both or neither)");
  // An open box, a fixed particle: refused at the first step.
  for (const auto& [scene, message] : std::vector<std::pair<std::string, std::string>>{
           {"simulation: { dt: 0.005, steps: 1, solver: { type: nose_hoover, kT: 1, tdamp: 0.5, "
            "pressure: 1, pdamp: 5 } }\nparticles:\n  - { position: [0, 0, 0], mass: 1 }\n  - { "
            "position: [1.1, 0, 0], mass: 1 }\nforces:\n  - { type: lennard_jones }\n",
            "nose_hoover: the barostat (pressure) needs a box periodic along every axis; axis x "
            "is open (expected simulation.box with periodic: [true, true, true])"},
           {"simulation: { dt: 0.005, steps: 1, solver: { type: nose_hoover, kT: 1, tdamp: 0.5, "
            "pressure: 1, pdamp: 5 }, box: { min: [0, 0, 0], max: [6, 6, 6], periodic: [true, "
            "true, true] } }\nparticles:\n  - { position: [1, 1, 1], mass: 1, fixed: true }\n  - "
            "{ position: [2.1, 1, 1], mass: 1 }\nforces:\n  - { type: lennard_jones }\n",
            "nose_hoover: the barostat (pressure) dilates every particle with the box, and "
            "particle 0 is fixed (expected no fixed particles)"}}) {
    Scene s = test::load_text(scene);
    Stepper stepper(*s.system, *s.solver, s.solver_label);
    EXPECT_FALSE(stepper.step_to(0.005));
    EXPECT_NE(stepper.fault().what.find(message), std::string::npos) << stepper.fault().what;
  }
}

}  // namespace
}  // namespace pdyn
