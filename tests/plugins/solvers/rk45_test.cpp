// rk45 (Dormand-Prince 5(4)): error control, dense output at frame times,
// rejections, FSAL, dt_min, checkpoint state and parameter checks, on the
// damped harmonic oscillator of support/oscillator.hpp.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <fstream>
#include <iostream>
#include <map>

#include "pdyn/error.hpp"
#include "pdyn/host/assembly.hpp"
#include "pdyn/host/runner.hpp"
#include "plugins/solvers/solver_support.hpp"

namespace pdyn {
namespace {

test::Oscillator Damped() {
  test::Oscillator o;
  o.k = 0.2;  // kg/s
  return o;
}

std::string Rk45(double rtol, const std::string& extra = "") {
  return "{ type: rk45, rtol: " + test::Num(rtol) + ", atol: " + test::Num(rtol * 1e-2) + extra +
         " }";
}

// Error at the end of a 10 s run (about 3 periods) for a given rtol.
double EndError(double rtol, StepCounts* counts) {
  const test::Oscillator osc = Damped();
  Scene scene = test::load_text(osc.scene(Rk45(rtol), "dt: 0.01, duration: 10"));
  const RunResult r = run_scene(scene);
  EXPECT_EQ(r.exit_code, 0) << r.message;
  EXPECT_EQ(scene.system->time(), 10.0);
  *counts = r.counts;
  return osc.error(*scene.system);
}

TEST(Rk45, ErrorScalesWithRtol) {
  std::cout << "rk45 on the damped oscillator, error at t = 10 s:\n";
  double previous = 0.0;
  for (const double rtol : {1e-4, 1e-6, 1e-8, 1e-10}) {
    StepCounts c;
    const double e = EndError(rtol, &c);
    std::cout << fmt::format("  rtol {:g}: error {:.3e}, {} accepted, {} rejected steps", rtol, e,
                             c.accepted, c.rejected);
    if (previous > 0.0) {
      std::cout << fmt::format(", {:.1f}x smaller than at rtol {:g}", previous / e, rtol * 100);
      // Tightening rtol (and atol) 100x must cut the error at least 30x.
      EXPECT_GE(previous / e, 30.0) << "rtol " << rtol;
    }
    std::cout << "\n";
    EXPECT_GT(c.accepted, 0);
    previous = e;
  }
}

// Frames are due at multiples of every * dt; with dense output they land
// exactly there (the same doubles the runner computes, printed with 17
// digits), and their states are accurate even though the steps are longer
// than the frame spacing.
TEST(Rk45, OutputFramesLandExactlyOnTheirTimes) {
  const test::Oscillator osc = Damped();
  constexpr double kRtol = 1e-6;
  const auto dir = test::temp_dir("rk45-frames");
  const auto csv = dir / "frames.csv";
  constexpr double kOutputDt = 0.01;
  constexpr int kEvery = 7;
  Scene scene = test::load_text(osc.scene(Rk45(kRtol), "dt: 0.01, duration: 3") +
                                "output: { path: " + csv.string() +
                                ", every: " + std::to_string(kEvery) + " }\n");
  const RunResult r = run_scene(scene);
  ASSERT_EQ(r.exit_code, 0) << r.message;

  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);  // header
  std::vector<std::string> times;
  double worst = 0.0;
  const double w0 = std::sqrt(osc.ks / osc.mass);
  while (std::getline(in, line)) {
    // t,id,x,y,z,vx,vy,vz; particle 1 is the oscillator.
    std::vector<std::string> f;
    std::size_t start = 0;
    for (std::size_t comma; (comma = line.find(',', start)) != std::string::npos;
         start = comma + 1) {
      f.push_back(line.substr(start, comma - start));
    }
    f.push_back(line.substr(start));
    ASSERT_EQ(f.size(), 8u) << line;
    if (f[1] != "1") continue;
    times.push_back(f[0]);
    const double t = std::stod(f[0]);
    const Vec3 x(std::stod(f[2]), std::stod(f[3]), std::stod(f[4]));
    const Vec3 v(std::stod(f[5]), std::stod(f[6]), std::stod(f[7]));
    worst = std::max({worst, (x - osc.x(t)).lpNorm<Eigen::Infinity>(),
                      (v - osc.v(t)).lpNorm<Eigen::Infinity>() / w0});
  }
  // Frames at 0, 0.07, ..., 2.94 and the final one at 3.
  const int n_frames = static_cast<int>(3.0 / (kEvery * kOutputDt)) + 1;
  ASSERT_EQ(static_cast<int>(times.size()), n_frames + 1);
  for (int m = 0; m < n_frames; ++m) {
    const double expected = static_cast<double>(m) * (static_cast<double>(kEvery) * kOutputDt);
    EXPECT_EQ(times[static_cast<std::size_t>(m)], fmt::format("{:.17g}", expected))
        << "frame " << m;
  }
  EXPECT_EQ(times.back(), "3");
  std::cout << fmt::format(
      "rk45 dense output: {} frames every {} s from {} accepted steps ({} rejected); largest "
      "frame error against the closed form {:.3e}\n",
      times.size(), kEvery * kOutputDt, r.counts.accepted, r.counts.rejected, worst);
  // Fewer steps than frames: frames come from the continuous extension
  // inside steps, and are as accurate as the steps (a few rtol).
  EXPECT_LT(r.counts.accepted, static_cast<std::int64_t>(times.size()));
  EXPECT_LT(worst, 10 * kRtol);
}

// A first step far too long for the tolerance is rejected and retried.
TEST(Rk45, RejectsStepsThatMissTheTolerance) {
  const test::Oscillator osc = Damped();
  Scene scene = test::load_text(osc.scene(Rk45(1e-9), "dt: 1.0, duration: 2"));
  const RunResult r = run_scene(scene);
  ASSERT_EQ(r.exit_code, 0) << r.message;
  std::cout << "rk45 from a 1 s first guess at rtol 1e-9: " << r.counts.accepted << " accepted, "
            << r.counts.rejected << " rejected\n";
  EXPECT_GE(r.counts.rejected, 1);
  EXPECT_LT(osc.error(*scene.system), 1e-7);
}

// Counts force evaluations: first same as last means 6 per attempted step,
// plus one for the very first k1.
class CountingForce final : public Force {
 public:
  void add_forces(const ParticleView&, Eigen::Ref<Matrix3X>) override { ++calls; }
  std::int64_t calls = 0;
};

TEST(Rk45, ReusesTheLastStageAsTheNextFirst) {
  const test::Oscillator osc = Damped();
  Scene scene = test::load_text(osc.scene(Rk45(1e-8), "dt: 0.01, duration: 5"));
  auto counter = std::make_shared<CountingForce>();
  SystemAssembly(*scene.system).add_force(counter, "counter");
  const RunResult r = run_scene(scene);
  ASSERT_EQ(r.exit_code, 0) << r.message;
  EXPECT_EQ(counter->calls, 1 + 6 * (r.counts.accepted + r.counts.rejected));
}

TEST(Rk45, StepBelowDtMinIsAClearError) {
  // A spring of w = 1e4 rad/s at rtol 1e-10 needs steps far below 1 ms:
  // 10 g on ks = 1e6 N/m, rest 1 m, stretched by 0.1 m, from rest.
  test::Oscillator stiff = test::Oscillator::Along(Vec3::UnitX(), 0.1, 0.0);
  stiff.mass = 1.0e-2;
  stiff.ks = 1.0e6;
  stiff.rest = 1.0;
  Scene scene = test::load_text(
      stiff.scene("{ type: rk45, rtol: 1.0e-10, dt_min: 1.0e-3 }", "dt: 0.01, duration: 1"));
  // The solver throws pdyn::Error; the runner stops with exit code 3.
  const RunResult r = run_scene(scene);
  std::cout << "rk45 dt_min: exit " << r.exit_code << ": " << r.message << "\n";
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_NE(r.message.find("rk45: the step size fell to 0.0004 s at t = 0 s, below dt_min = "
                           "0.001 s"),
            std::string::npos)
      << r.message;
  // The system is left at the last accepted state, not at a rejected stage.
  EXPECT_EQ(scene.system->time(), 0.0);
  EXPECT_EQ(scene.system->positions()(0, 1), 1.1);
}

// save_state carries the next step size and the controller's memory, so a
// resumed run takes bit-identical steps.
TEST(Rk45, ResumesBitIdenticallyFromItsSavedState) {
  const test::Oscillator osc = Damped();
  const std::string text = osc.scene(Rk45(1e-8), "dt: 0.01, duration: 10");
  constexpr double kStop = 10.0;
  auto advance = [&](Scene& s, int n) {
    for (int k = 0; k < n; ++k) s.solver->advance(*s.system, kStop, 0.01);
  };
  Scene straight = test::load_text(text);
  advance(straight, 40);

  Scene first = test::load_text(text);
  advance(first, 25);
  const std::vector<std::uint8_t> saved = first.solver->save_state();
  Eigen::VectorXd y = first.system->state();

  Scene resumed = test::load_text(text);
  resumed.system->set_state(y);
  resumed.system->set_time(first.system->time());
  resumed.solver->restore_state(saved);
  advance(resumed, 15);
  EXPECT_EQ(resumed.system->time(), straight.system->time());
  EXPECT_TRUE(resumed.system->state() == straight.system->state());
  EXPECT_EQ(resumed.solver->counts().accepted, straight.solver->counts().accepted);

  // Without the saved state the steps differ (the first is the dt hint).
  Scene fresh = test::load_text(text);
  fresh.system->set_state(y);
  fresh.system->set_time(first.system->time());
  advance(fresh, 15);
  EXPECT_NE(fresh.system->time(), straight.system->time());

  const std::vector<std::uint8_t> junk = {1, 2, 3};
  EXPECT_THROW(fresh.solver->restore_state(junk), Error);
}

TEST(Rk45, RejectsDtMaxBelowDtMin) {
  try {
    test::load_text(test::Oscillator{}.scene("{ type: rk45, dt_min: 0.1, dt_max: 0.01 }",
                                             "dt: 0.01, steps: 1"));
    FAIL() << "expected SceneError";
  } catch (const SceneError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("dt_max: is 0.01 s, smaller than dt_min = 0.1 s"), std::string::npos)
        << what;
  }
}

TEST(Rk45, IsAdaptiveUnlessAskedForFixedSteps) {
  Scene adaptive =
      test::load_text(test::Oscillator{}.scene("{ type: rk45 }", "dt: 0.01, steps: 1"));
  EXPECT_TRUE(adaptive.solver->adaptive());
  Scene fixed = test::load_text(
      test::Oscillator{}.scene("{ type: rk45, fixed_step: true }", "dt: 0.01, steps: 10"));
  EXPECT_FALSE(fixed.solver->adaptive());
  const RunResult r = run_scene(fixed);
  EXPECT_EQ(r.steps_done, 10);
  EXPECT_EQ(fixed.solver->counts().accepted, 10);
}

}  // namespace
}  // namespace pdyn
