// Energy over 100,000 steps of an undamped oscillator (m = 1 kg, ks = 1 N/m,
// so w = 1 rad/s and T = 2 pi s) at dt = T/100, i.e. 1000 periods.
//
// Symplectic methods keep the energy in a band of fixed width with no
// secular drift: they exactly conserve a modified energy H~ = H + O(h^p)
// (Hairer, Lubich & Wanner, "Geometric Numerical Integration", IX.8). For
// this oscillator the band's relative half-width is about h w / 2 = 3.1e-2
// for symplectic Euler and (h w)^2 / 8 = 4.9e-4 for velocity Verlet.
// Explicit Euler multiplies the energy by exactly 1 + (h w)^2 every step, so
// after N steps it has grown by (1 + (h w)^2)^N ~ 1e171.
#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>
#include <numbers>

#include "plugins/solvers/solver_support.hpp"

namespace pdyn {
namespace {

constexpr int kEnergySteps = 100000;
const double kEnergyDt = 2.0 * std::numbers::pi / 100.0;  // T / 100

test::Oscillator Undamped() {
  test::Oscillator o;
  o.mass = 1.0;
  o.ks = 1.0;
  return o;
}

// Energy after every step (index 0: the initial energy).
std::vector<double> EnergyHistory(const std::string& solver) {
  const test::Oscillator osc = Undamped();
  Scene scene = test::load_text(
      osc.scene("{ type: " + solver + " }",
                "dt: " + test::Num(kEnergyDt) + ", steps: " + std::to_string(kEnergySteps)));
  System& sys = *scene.system;
  std::vector<double> e;
  e.reserve(kEnergySteps + 1);
  e.push_back(sys.kinetic_energy() + sys.potential_energy());
  for (int k = 1; k <= kEnergySteps; ++k) {
    test::TakeStep(scene, k, kEnergyDt);
    e.push_back(sys.kinetic_energy() + sys.potential_energy());
  }
  return e;
}

struct Band {
  double lo, hi, mean;
  double width() const { return hi - lo; }
};

Band BandOf(const std::vector<double>& e, std::size_t begin, std::size_t end) {
  Band b{e[begin], e[begin], 0.0};
  for (std::size_t k = begin; k < end; ++k) {
    b.lo = std::min(b.lo, e[k]);
    b.hi = std::max(b.hi, e[k]);
    b.mean += e[k];
  }
  b.mean /= static_cast<double>(end - begin);
  return b;
}

// Checks a symplectic solver's energy: bounded band, no drift, and the
// largest relative error below `max_relative_error`.
void ExpectBoundedEnergy(const std::string& solver, double max_relative_error) {
  const std::vector<double> e = EnergyHistory(solver);
  const double e0 = e.front();
  const std::size_t tenth = kEnergySteps / 10;
  const Band first = BandOf(e, 0, tenth + 1),
             last = BandOf(e, kEnergySteps - tenth, kEnergySteps + 1);
  double worst = 0.0;
  for (const double x : e) worst = std::max(worst, std::abs(x - e0) / e0);
  std::cout << solver << " energy over " << kEnergySteps << " steps at dt = T/100: band width "
            << first.width() / e0 << " (first tenth), " << last.width() / e0
            << " (last tenth) of E0; mean drift " << (last.mean - first.mean) / e0
            << " of E0; max relative error " << worst << "\n";
  // The band does not widen: no more than 1% wider at the end (round-off
  // and the sampling phase of the band's period shift it slightly).
  EXPECT_LE(last.width(), 1.01 * first.width()) << solver;
  // No secular drift: the band's centre moves by less than 1% of its width.
  EXPECT_LT(std::abs(last.mean - first.mean), 0.01 * first.width()) << solver;
  EXPECT_LT(worst, max_relative_error) << solver;
}

TEST(EnergyConservation, VerletStaysInABoundedBand) { ExpectBoundedEnergy("verlet", 2e-3); }

TEST(EnergyConservation, SymplecticEulerStaysInABoundedBand) {
  ExpectBoundedEnergy("symplectic_euler", 5e-2);
}

TEST(EnergyConservation, EulerGrowsWithoutBound) {
  const std::vector<double> e = EnergyHistory("euler");
  const double hw2 = kEnergyDt * kEnergyDt;  // (h w)^2 with w = 1
  std::size_t increases = 0;
  for (std::size_t k = 1; k < e.size(); ++k) increases += e[k] > e[k - 1] ? 1 : 0;
  const double log_growth = std::log(e.back() / e.front());
  const double predicted = kEnergySteps * std::log1p(hw2);
  std::cout << "euler energy over " << kEnergySteps
            << " steps at dt = T/100: E/E0 = " << e.back() / e.front() << " (ln " << log_growth
            << "; (1 + (h w)^2)^N predicts ln " << predicted << "); grew on " << increases << " of "
            << kEnergySteps << " steps\n";
  EXPECT_EQ(increases, static_cast<std::size_t>(kEnergySteps));  // every single step
  EXPECT_NEAR(log_growth, predicted, 1e-6 * predicted);
  EXPECT_GT(e.back() / e.front(), 1e100);
}

}  // namespace
}  // namespace pdyn
