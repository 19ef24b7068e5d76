// A scene's `velocities:` section (pdyn/host/velocities.hpp): velocities
// drawn from Maxwell-Boltzmann at a temperature, as LAMMPS's `velocity
// create ... mom yes`: the distribution passes a Kolmogorov-Smirnov test,
// the momentum is zero and the temperature exact, the draw is the same bits
// for a seed whatever the thread count, and each bad value gets its located
// error.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "pdyn/system.hpp"
#include "pdyn/thermo.hpp"
#include "support/statistics.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

// n particles on a lattice, the first half of mass 1 kg, the rest 4 kg, and
// the last one nailed; `velocities` is the section's mapping.
std::string gas(const std::string& velocities, int side = 20, const std::string& extra = "") {
  return "simulation: { dt: 0.001, steps: 1, solver: { type: verlet }" + extra +
         " }\n"
         "particles:\n"
         "  - lattice: { origin: [0, 0, 0], n: [" +
         std::to_string(side) + ", " + std::to_string(side) + ", " + std::to_string(side / 2) +
         "], spacing: 1, mass: 1, name: light }\n"
         "  - lattice: { origin: [0, 0, 100], n: [" +
         std::to_string(side) + ", " + std::to_string(side) + ", " + std::to_string(side / 2) +
         "], spacing: 1, mass: 4, name: heavy }\n"
         "  - { position: [0, 0, -5], mass: 1, fixed: true, velocity: [0, 0, 0] }\n"
         "velocities: " +
         velocities + "\n";
}

TEST(Velocities, AreMaxwellBoltzmannAtTheTemperature) {
  // Unscaled, momentum kept: each component of v_i sqrt(m_i / kT) is a
  // standard normal deviate.
  const double kT = 1.380649e-23 * 300.0;
  const Scene scene =
      test::load_text(gas("{ temperature: 300, seed: 7, zero_momentum: false, "
                          "scale: false }"));
  const System& s = *scene.system;
  ASSERT_EQ(s.size(), 8001);
  std::vector<double> z;
  double sum = 0.0, sum2 = 0.0;
  for (Index i = 0; i + 1 < s.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      const double u = s.velocities()(k, i) * std::sqrt(s.masses()(i) / kT);
      z.push_back(u);
      sum += u;
      sum2 += u * u;
    }
  }
  const double n = static_cast<double>(z.size());
  const double d = test::ks_normal(z);
  std::cout << "velocities: KS D = " << d
            << " (critical at 1%: " << test::ks_critical_1percent(z.size()) << "), mean " << sum / n
            << ", variance " << sum2 / n << " over " << z.size() << " components\n";
  EXPECT_LT(d, test::ks_critical_1percent(z.size()));
  EXPECT_LT(std::abs(sum / n), 4.0 / std::sqrt(n));               // mean 0 within 4 sigma
  EXPECT_LT(std::abs(sum2 / n - 1.0), 4.0 * std::sqrt(2.0 / n));  // variance 1 within 4 sigma
  EXPECT_EQ(s.velocities().col(s.size() - 1), Vec3::Zero());      // the nailed particle
}

TEST(Velocities, HaveZeroMomentumAndExactlyTheTemperature) {
  // LAMMPS's default: momentum removed, then scaled to T with 3 N - 3
  // degrees of freedom (N the free particles), which the energy writer's
  // temperature (pdyn/thermo.hpp, extra_dof 3) reports back.
  const Scene scene = test::load_text(gas("{ kT: 1.44, seed: 87287 }"));
  const System& s = *scene.system;
  const Vec3 p = s.velocities() * s.masses();
  const Thermo th = thermo(s.view(), 0.0);
  double scale = 0.0;  // momentum per particle, for the bound
  for (Index i = 0; i < s.size(); ++i) scale += s.masses()(i) * s.velocities().col(i).norm();
  std::cout << "velocities: kT = " << th.kT
            << " J (asked 1.44), |P| / sum m|v| = " << p.norm() / scale << ", dof " << th.dof
            << "\n";
  EXPECT_NEAR(th.kT, 1.44, 1e-14);
  EXPECT_EQ(th.dof, 3.0 * 8000 - 3);
  EXPECT_LT(p.norm(), 1e-15 * scale);
  // Kelvin: the same draw with k_B T = 1.380649e-23 * 300 J.
  const Scene kelvin = test::load_text(gas("{ temperature: 300, seed: 87287 }"));
  EXPECT_NEAR(thermo(kelvin.system->view(), 0.0).temperature, 300.0, 1e-11);
}

TEST(Velocities, AreTheSameBitsForASeedWhateverTheThreadCount) {
  const Scene a = test::load_text(gas("{ kT: 2, seed: 11 }", 20, ", threads: 1"));
  const Scene b = test::load_text(gas("{ kT: 2, seed: 11 }", 20, ", threads: 2"));
  const Scene c = test::load_text(gas("{ kT: 2, seed: 12 }"));
  EXPECT_TRUE((a.system->velocities().array() == b.system->velocities().array()).all());
  const Index free = a.system->size() - 1;  // the last one is nailed: zero in both
  EXPECT_FALSE((a.system->velocities().leftCols(free).array() ==
                c.system->velocities().leftCols(free).array())
                   .any());
}

TEST(Velocities, AGroupGetsThemAndTheOthersKeepTheirs) {
  const Scene scene = test::load_text(gas("{ kT: 1, seed: 3, group: heavy }", 4));
  const System& s = *scene.system;
  const Index light = 4 * 4 * 2;
  for (Index i = 0; i < light; ++i) EXPECT_EQ(s.velocities().col(i), Vec3::Zero());
  Vec3 p = Vec3::Zero();
  double twice_k = 0.0;
  for (Index i = light; i < 2 * light; ++i) {
    p += s.masses()(i) * s.velocities().col(i);
    twice_k += s.masses()(i) * s.velocities().col(i).squaredNorm();
  }
  EXPECT_LT(p.norm(), 1e-13);
  EXPECT_NEAR(twice_k / (3.0 * static_cast<double>(light) - 3.0), 1.0, 1e-14);
}

TEST(Velocities, EachBadValueGetsItsLocatedError) {
  const std::string both = "(expected temperature: T in K, or kT: k_B T in J for reduced units)";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"{ temperature: -1 }",
       "test.yaml:6:28: velocities.temperature: -1 is out of range (expected a number >= 0 in K)"},
      {"{ kT: -0.5 }",
       "test.yaml:6:19: velocities.kT: -0.5 is out of range (expected a number >= 0 in J)"},
      {"{ temperature: 1, kT: 2 }",
       "test.yaml:6:35: velocities.kT: given with temperature (expected one of temperature: T in "
       "K, or kT: k_B T in J for reduced units)"},
      {"{ seed: 3 }", "test.yaml:6:13: velocities.temperature: no temperature given " + both},
      {"{ kT: 1, seed: -1 }",
       "test.yaml:6:28: velocities.seed: -1 is out of range (expected a whole number in [0, "
       "4294967295])"},
      {"{ kT: 1, seed: 4294967296 }",
       "test.yaml:6:28: velocities.seed: 4294967296 is out of range (expected a whole number in "
       "[0, 4294967295])"},
      {"{ kT: 1, group: nope }",
       "test.yaml:6:29: velocities.group: no group is named 'nope' (expected one of: heavy, "
       "light)"},
      {"3",
       "test.yaml:6:13: velocities: '3' is not a mapping (expected velocities: { "
       "temperature: T, seed: N })"},
  };
  for (const auto& [section, message] : cases) {
    EXPECT_EQ(test::load_problems(gas(section, 2)), message) << section;
  }
  // One free particle has no thermal motion left once its momentum is removed.
  EXPECT_EQ(test::load_problems("simulation: { dt: 0.001, steps: 1 }\n"
                                "particles:\n"
                                "  - { position: [0, 0, 0], mass: 1 }\n"
                                "velocities: { kT: 1 }\n"),
            "test.yaml:4:13: velocities: 1 free particle has no thermal degrees of freedom once "
            "the momentum is removed (expected at least 2, or zero_momentum: false)");
}

}  // namespace
}  // namespace pdyn
