// lennard_jones through the pair-force SDK (pdyn/pair.hpp): the analytic
// law for two particles, the neighbor-list sum equal to a brute-force sum
// over all pairs (open and periodic), bit-identical forces for 1-4 threads,
// energy conservation of a small Lennard-Jones liquid under velocity
// Verlet, the cutoff that does not fit a periodic box refused naming the
// key, and a blow-up (two particles on top of each other) naming the force.
// Mixtures (`pair_coeff`, `mix`): each type pair's analytic law with its
// own, mixed or fallback coefficients and cutoff, the list sum of a random
// two-type configuration equal to the brute-force sum, one row for type 0
// bit-identical to the one-type law, and every bad row a located scene
// error with its exact text.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <utility>

#include "pdyn/error.hpp"
#include "pdyn/host/assembly.hpp"
#include "pdyn/host/resolve.hpp"
#include "pdyn/host/threads.hpp"
#include "pdyn/pair.hpp"
#include "pdyn/parallel.hpp"
#include "pdyn/system.hpp"
#include "plugins/forces/force_support.hpp"
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
  SystemAssembly(sys).set_particles(
      x, Matrix3X::Zero(3, x.cols()), Eigen::VectorXd::Ones(x.cols()),
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
      SystemAssembly(sys).set_domain(d);
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
      SystemAssembly(sys).wrap_positions();
    }
  }
}

// Forces of lennard_jones with `given` on 21,952 particles of a periodic
// lattice (the threaded path), every third of type 1 if `two_types`, on 1
// to 4 threads: bit-identical to one thread's, added onto forces already
// there.
void ExpectBitIdenticalForOneToFourThreads(std::uint64_t seed, const Params& given,
                                           bool two_types) {
  System sys;
  set(sys, lattice(28, 1.1, seed));
  if (two_types) {
    std::vector<std::int32_t> type(static_cast<std::size_t>(sys.size()));
    for (std::size_t i = 0; i < type.size(); ++i) type[i] = static_cast<std::int32_t>(i % 3 == 0);
    SystemAssembly(sys).set_types(type);
  }
  Domain d;
  d.max = Vec3::Constant(28 * 1.1);
  d.periodic = {true, true, true};
  SystemAssembly(sys).set_domain(d);
  Matrix3X reference;
  for (const int threads : {1, 2, 3, 4}) {
    set_threads(threads);
    auto force = make(sys, given);
    Matrix3X f = Matrix3X::Constant(3, sys.size(), 0.125);
    force->add_forces(sys.view(), f);
    if (threads == 1) {
      reference = f;
    } else {
      EXPECT_TRUE(f.cwiseEqual(reference).all()) << threads << " threads";
    }
  }
  set_threads(available_threads());
}

TEST(LennardJones, ForcesAreBitIdenticalForOneToFourThreads) {
  ExpectBitIdenticalForOneToFourThreads(11, Params{}, false);
}

// The same Lennard-Jones arithmetic with and without
// evaluate_beyond_cutoff (pdyn/pair.hpp): the selecting loop and the
// branching loop give the same bits on a jittered periodic lattice (21,952
// particles; the shell at sqrt(5) spacings straddles the cutoff, the next
// lies between cutoff and reach), for 1 and 2 threads; and a law whose value
// beyond the cutoff is NaN changes nothing.
template <bool Select, bool NanBeyond>
struct TestLaw {
  static constexpr bool evaluate_beyond_cutoff = Select;
  PairTerm operator()(double r2, std::int32_t, std::int32_t) const {
    if (NanBeyond && !(r2 < 6.25)) return {std::nan(""), std::nan("")};
    const double r2inv = 1.0 / r2, r6inv = r2inv * r2inv * r2inv;
    return {4.0 * r6inv * (r6inv - 1.0), r6inv * (48.0 * r6inv - 24.0) * r2inv};
  }
};

template <class Law>
Matrix3X pair_forces(const System& sys) {
  PairForce<Law> force(Law{}, 2.5, 0.3);
  Matrix3X f = Matrix3X::Constant(3, sys.size(), 0.125);
  force.add_forces(sys.view(), f);
  return f;
}

// 21,952 particles on a jittered simple cubic lattice of 1.1 in its
// periodic box.
void jittered_periodic_lattice(System& sys) {
  set(sys, lattice(28, 1.1, 3));
  Domain d;
  d.max = Vec3::Constant(28 * 1.1);
  d.periodic = {true, true, true};
  SystemAssembly(sys).set_domain(d);
}

TEST(LennardJones, TheSelectingPairLoopGivesTheBranchingLoopsBits) {
  System sys;
  jittered_periodic_lattice(sys);
  for (const int threads : {1, 2}) {
    set_threads(threads);
    const Matrix3X branching = pair_forces<TestLaw<false, false>>(sys);
    ASSERT_TRUE(branching.allFinite());
    EXPECT_NE(branching, Matrix3X::Constant(3, sys.size(), 0.125));
    const Matrix3X selecting = pair_forces<TestLaw<true, false>>(sys);
    const Matrix3X nan_beyond = pair_forces<TestLaw<true, true>>(sys);
    EXPECT_TRUE(selecting.cwiseEqual(branching).all()) << threads << " threads";
    EXPECT_TRUE(nan_beyond.cwiseEqual(branching).all()) << threads << " threads";
  }
  set_threads(available_threads());
}

// The virial a barostat reads at every step (PairForce::virial): for a law
// the loop selects on, summed in blocks over fixed chunks of rows on the
// threads. The same bits for 1 to 4 threads (21,952 particles: beyond the
// one-thread threshold), and the branching law's sum of (x_i - x_j) . f_ij
// to rounding.
TEST(LennardJones, TheVirialIsTheSameBitsForOneToFourThreadsAndTheBranchingSum) {
  System sys;
  jittered_periodic_lattice(sys);
  std::vector<double> selected;
  for (const int threads : {1, 2, 3, 4}) {
    set_threads(threads);
    PairForce<TestLaw<true, false>> force(TestLaw<true, false>{}, 2.5, 0.3);
    selected.push_back(force.virial(sys.view()));
  }
  set_threads(1);
  PairForce<TestLaw<false, false>> branching(TestLaw<false, false>{}, 2.5, 0.3);
  const double reference = branching.virial(sys.view());
  set_threads(available_threads());
  for (const double w : selected) EXPECT_EQ(w, selected.front());
  EXPECT_NE(reference, 0.0);
  EXPECT_NEAR(selected.front(), reference, 1e-12 * std::abs(reference));
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
  SystemAssembly(sys).set_domain(d);
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

// df/dx from the law's force_over_r_slope (PairForce::add_jacobians) equals
// central differences of the forces (h = 1e-6 sigma) to 1e-6 of the largest
// block, for one type and for a mixture, on 125 particles of a jittered
// lattice filling a periodic box (pairs across the faces included).

TEST(LennardJones, AnalyticJacobiansMatchCentralDifferences) {
  Params mixture;
  mixture.set("pair_coeff", std::vector<std::string>{"0 0 1 1", "1 1 0.5 0.9 2.0"});
  for (const Params& given : {Params{}, mixture}) {
    System sys;
    set(sys, lattice(5, 1.15, 5));
    std::vector<std::int32_t> type(125);
    for (std::size_t i = 0; i < type.size(); ++i) type[i] = static_cast<std::int32_t>(i % 3 == 0);
    SystemAssembly(sys).set_types(type);
    Domain d;
    d.max = Vec3::Constant(5 * 1.15);  // 5.75 >= 2 (2.5 + 0.3)
    d.periodic = {true, true, true};
    SystemAssembly(sys).set_domain(d);
    auto force = make(sys, given);
    test::DenseSink sink(sys.size());
    ASSERT_TRUE(force->add_jacobians(sys.view(), sink));
    const double h = 1e-6;
    Eigen::MatrixXd numeric(3 * sys.size(), 3 * sys.size());
    for (Index k = 0; k < sys.size(); ++k) {
      for (int c = 0; c < 3; ++c) {
        const double saved = sys.positions()(c, k);
        sys.positions()(c, k) = saved + h;
        const Matrix3X plus = forces(*force, sys);
        sys.positions()(c, k) = saved - h;
        const Matrix3X minus = forces(*force, sys);
        sys.positions()(c, k) = saved;
        const Matrix3X diff = (plus - minus) / (2 * h);
        numeric.col(3 * k + c) = Eigen::Map<const Eigen::VectorXd>(diff.data(), 3 * sys.size());
      }
    }
    const double scale = sink.dfdx.cwiseAbs().maxCoeff();
    EXPECT_GT(scale, 1.0);
    EXPECT_LT((sink.dfdx - numeric).cwiseAbs().maxCoeff(), 1e-6 * scale);
    EXPECT_TRUE(sink.dfdv.isZero(0.0)) << "a position-only law reported df/dv";
  }
}

TEST(LennardJones, ACutoffThatDoesNotFitThePeriodicBoxIsRefused) {
  System sys;
  set(sys, lattice(2, 1.1, 1));
  Domain d;
  d.max = Vec3(10, 5, 10);
  d.periodic = {true, true, false};
  SystemAssembly(sys).set_domain(d);
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

// ---- mixtures ----

// One type pair's coefficients: epsilon (J), sigma (m), cutoff (m).
struct Coeff {
  double eps, sigma, rc;
};

// U (J) and -U'(r) (N) of one pair at distance r, shifted or not.
std::pair<double, double> analytic(const Coeff& c, double r, bool shift) {
  if (!(r < c.rc)) return {0.0, 0.0};
  const double sr6 = std::pow(c.sigma / r, 6.0), sc6 = std::pow(c.sigma / c.rc, 6.0);
  const double u = 4 * c.eps * (sr6 * sr6 - sr6) - (shift ? 4 * c.eps * (sc6 * sc6 - sc6) : 0.0);
  return {u, 24 * c.eps * (2 * sr6 * sr6 - sr6) / r};
}

// Two particles of types ta and tb at distance r: the force on the second
// along the line (> 0 repulsive), Newton's third law, and the energy.
std::pair<double, double> two_of_types(const Params& given, std::int32_t ta, std::int32_t tb,
                                       double r) {
  System sys;
  Matrix3X x = Matrix3X::Zero(3, 2);
  const Vec3 n(0.48, 0.6, 0.64);
  x.col(1) = r * n;
  set(sys, x);
  SystemAssembly(sys).set_types({ta, tb});
  auto force = make(sys, given);
  const Matrix3X f = forces(*force, sys);
  EXPECT_EQ(Vec3(f.col(0) + f.col(1)), Vec3::Zero());
  EXPECT_NEAR((Vec3(f.col(1)) - Vec3(f.col(1)).dot(n) * n).norm(), 0.0,
              1e-14 * (1 + f.col(1).norm()));  // along the line
  return {*force->potential_energy(sys.view()), Vec3(f.col(1)).dot(n)};
}

void expect_law(const Params& given, std::int32_t ta, std::int32_t tb, const Coeff& c, bool shift) {
  for (const double r : {0.95 * c.sigma, std::pow(2.0, 1.0 / 6.0) * c.sigma, 1.5 * c.sigma,
                         c.rc - 0.01, c.rc + 0.01}) {
    const auto [u, fr] = two_of_types(given, ta, tb, r);
    const auto [want_u, want_fr] = analytic(c, r, shift);
    EXPECT_NEAR(fr, want_fr, 1e-12 * (1 + std::abs(want_fr)))
        << "types " << ta << " " << tb << ", r = " << r;
    EXPECT_NEAR(u, want_u, 1e-12 * (1 + std::abs(want_u)))
        << "types " << ta << " " << tb << ", r = " << r;
  }
}

TEST(LennardJones, BinaryMixtureFollowsTheAnalyticLawForEachTypePair) {
  // Types 1 and 2 (no type 0): 1 1 at the default cutoff 2.5, 2 2 at its own 2.2.
  const Coeff c11{1.0, 1.0, 2.5}, c22{0.5, 0.88, 2.2};
  for (const bool shift : {false, true}) {
    Params given;
    given.set("pair_coeff", std::vector<std::string>{"1 1 1.0 1.0", "2  2 0.5 0.88 2.2"});
    given.set("shift", shift);
    // Geometric mixing (the default, LAMMPS's): every coefficient's geometric mean.
    expect_law(given, 1, 1, c11, shift);
    expect_law(given, 2, 2, c22, shift);
    const Coeff geometric{std::sqrt(c11.eps * c22.eps), std::sqrt(c11.sigma * c22.sigma),
                          std::sqrt(c11.rc * c22.rc)};
    expect_law(given, 1, 2, geometric, shift);
    expect_law(given, 2, 1, geometric, shift);
    // Lorentz-Berthelot: the same epsilon, arithmetic means of sigma and rc.
    given.set("mix", std::string("arithmetic"));
    const Coeff arithmetic{std::sqrt(c11.eps * c22.eps), 0.5 * (c11.sigma + c22.sigma),
                           0.5 * (c11.rc + c22.rc)};
    expect_law(given, 2, 1, arithmetic, shift);
    expect_law(given, 2, 2, c22, shift);
    // A row for the cross pair wins over any mixing, written either way round.
    given.set("pair_coeff",
              std::vector<std::string>{"1 1 1.0 1.0", "2 2 0.5 0.88 2.2", "2 1 1.5 0.8 2.0"});
    expect_law(given, 1, 2, Coeff{1.5, 0.8, 2.0}, shift);
    expect_law(given, 1, 1, c11, shift);
  }
}

TEST(LennardJones, EpsilonAndSigmaGivenWithRowsCoverThePairsNoRowGives) {
  // Types 0 and 1; a row for 1 1 only. epsilon and sigma (with the default
  // cutoff) give 0 0; the cross pair 0 1 is their mix with 1 1, or with
  // mix: none the fallback itself.
  const Coeff fallback{2.0, 1.1, 2.5}, c11{0.5, 0.9, 2.0};
  Params given;
  given.set("pair_coeff", std::vector<std::string>{"1 1 0.5 0.9 2.0"});
  given.set("epsilon", fallback.eps);
  given.set("sigma", fallback.sigma);
  expect_law(given, 0, 0, fallback, false);
  expect_law(given, 1, 1, c11, false);
  expect_law(given, 0, 1,
             Coeff{std::sqrt(fallback.eps * c11.eps), std::sqrt(fallback.sigma * c11.sigma),
                   std::sqrt(fallback.rc * c11.rc)},
             false);
  given.set("mix", std::string("none"));
  expect_law(given, 0, 1, fallback, false);
  // Only sigma given: epsilon is 1 J, as without rows.
  Params sigma_only;
  sigma_only.set("pair_coeff", std::vector<std::string>{"1 1 0.5 0.9 2.0"});
  sigma_only.set("sigma", 1.1);
  expect_law(sigma_only, 0, 0, Coeff{1.0, 1.1, 2.5}, false);
}

// Forces and energy of the mixture by brute force: every pair, nearest
// image, the coefficients of its two types.
std::pair<Matrix3X, double> brute_force_mixture(const Matrix3X& x,
                                                const std::vector<std::int32_t>& type,
                                                const Domain& d, const Coeff (&c)[2][2],
                                                bool shift) {
  Matrix3X f = Matrix3X::Zero(3, x.cols());
  double u = 0.0;
  for (Index i = 0; i < x.cols(); ++i) {
    for (Index j = i + 1; j < x.cols(); ++j) {
      const Vec3 r = d.minimum_image(x.col(i) - x.col(j));
      const auto [uij, fr] = analytic(
          c[type[static_cast<std::size_t>(i)]][type[static_cast<std::size_t>(j)]], r.norm(), shift);
      f.col(i) += fr / r.norm() * r;
      f.col(j) -= fr / r.norm() * r;
      u += uij;
    }
  }
  return {f, u};
}

TEST(LennardJones, MixtureNeighborListSumEqualsTheBruteForceSum) {
  // A random mixture of types 0 and 1 on a jittered lattice; 0 1 from a row
  // with a cutoff between the self pairs' (the list reaches the largest).
  const Coeff c[2][2] = {{{1.0, 1.0, 2.5}, {1.4, 0.95, 2.3}}, {{1.4, 0.95, 2.3}, {0.6, 0.9, 2.0}}};
  for (const bool periodic : {false, true}) {
    SCOPED_TRACE(periodic ? "periodic" : "open");
    const int side = 8;
    const double spacing = 1.1;
    System sys;
    set(sys, lattice(side, spacing, 17));
    std::mt19937 rng(5);
    std::vector<std::int32_t> type(static_cast<std::size_t>(sys.size()));
    for (auto& t : type) t = std::bernoulli_distribution(0.3)(rng) ? 1 : 0;
    SystemAssembly(sys).set_types(type);
    Domain d;
    if (periodic) {
      d.max = Vec3::Constant(side * spacing);
      d.periodic = {true, true, true};
      SystemAssembly(sys).set_domain(d);
    }
    Params given;
    given.set("shift", true);
    given.set("pair_coeff",
              std::vector<std::string>{"0 0 1.0 1.0", "1 1 0.6 0.9 2.0", "0 1 1.4 0.95 2.3"});
    auto force = make(sys, given);
    std::normal_distribution<double> move(0.0, 0.04);
    for (int step = 0; step < 12; ++step) {
      const Matrix3X f = forces(*force, sys);
      const auto [want, want_u] = brute_force_mixture(sys.positions(), type, d, c, true);
      EXPECT_LE((f - want).cwiseAbs().maxCoeff(), 1e-10 * want.cwiseAbs().maxCoeff())
          << "step " << step;
      EXPECT_NEAR(*force->potential_energy(sys.view()), want_u, 1e-10 * sys.size())
          << "step " << step;
      for (Index i = 0; i < sys.size(); ++i) {
        sys.positions().col(i) += Vec3(move(rng), move(rng), move(rng));
      }
      SystemAssembly(sys).wrap_positions();
    }
    const auto* pf = dynamic_cast<const PairReference*>(force.get());
    ASSERT_NE(pf, nullptr);
    EXPECT_EQ(pf->pair_cutoff(), 2.5);  // the largest of the table's
  }
}

TEST(LennardJones, OneRowForTypeZeroIsTheOneTypeLawBitForBit) {
  // The table path does the one-type law's arithmetic: a scene that moves
  // its coefficients into a row gets the same forces, bit for bit.
  System sys;
  set(sys, lattice(6, 1.1, 3));
  Params one, rows;
  one.set("epsilon", 0.8);
  one.set("sigma", 1.05);
  one.set("shift", true);
  rows.set("pair_coeff", std::vector<std::string>{"0 0 0.8 1.05"});
  rows.set("shift", true);
  const Matrix3X a = forces(*make(sys, one), sys), b = forces(*make(sys, rows), sys);
  EXPECT_TRUE(a.cwiseEqual(b).all());
  EXPECT_EQ(*make(sys, one)->potential_energy(sys.view()),
            *make(sys, rows)->potential_energy(sys.view()));
}

TEST(LennardJones, MixtureForcesAreBitIdenticalForOneToFourThreads) {
  Params given;
  given.set("pair_coeff", std::vector<std::string>{"0 0 1 1", "1 1 0.5 0.9 2.0"});
  ExpectBitIdenticalForOneToFourThreads(13, given, true);
}

// Three particles of types 0, 1, 1 and a lennard_jones entry `entry`
// (flow-mapping keys after `type: lennard_jones`) on line 7; `box`: the
// simulation's extra keys.
std::string mixture_problems(const std::string& entry, const std::string& box = "",
                             const std::string& third_type = "1") {
  return test::load_problems("simulation: { dt: 0.01, steps: 1" + box +
                             " }\n"
                             "particles:\n"
                             "  - { position: [1, 1, 1], mass: 1, type: 0 }\n"
                             "  - { position: [2.1, 1, 1], mass: 1, type: 1 }\n"
                             "  - { position: [1, 2.1, 1], mass: 1, type: " +
                             third_type +
                             " }\n"
                             "forces:\n"
                             "  - { type: lennard_jones, " +
                             entry + " }\n");
}

TEST(LennardJones, BadPairCoefficientsAreLocatedSceneErrors) {
  struct Case {
    std::string entry, message;
  };
  const std::vector<Case> cases = {
      // Type 1's particles form 1 1, which no row, mixing or fallback gives.
      {"pair_coeff: ['0 0 1 1', '0 1 1 1'], mix: none",
       "test.yaml:7:40: forces[0].pair_coeff: no coefficients for the type pair 1 1, which the "
       "scene's particles form (expected a row '1 1 epsilon sigma', or epsilon and sigma for the "
       "pairs without a row)"},
      {"pair_coeff: ['0 0 1 1', '1 1 1 1'], mix: none",
       "test.yaml:7:40: forces[0].pair_coeff: no coefficients for the type pair 0 1, which the "
       "scene's particles form (expected a row '0 1 epsilon sigma' (mix: none), or epsilon and "
       "sigma for the pairs without a row)"},
      // One particle of type 0 forms no 0 0 pair, but 0 1 with type 1's.
      {"pair_coeff: ['1 1 1 1']",
       "test.yaml:7:40: forces[0].pair_coeff: no coefficients for the type pair 0 1, which the "
       "scene's particles form (expected a row '0 1 epsilon sigma' or rows for 0 0 and 1 1 to "
       "mix, or epsilon and sigma for the pairs without a row)"},
      {"pair_coeff: ['0 0 1 1', '0 1 1']",
       "test.yaml:7:52: forces[0].pair_coeff[1]: '0 1 1': 3 fields (expected 'I J epsilon sigma' "
       "or 'I J epsilon sigma cutoff': two types, then numbers in J and m)"},
      {"pair_coeff: ['0 0 1 1 2.5 7']",
       "test.yaml:7:41: forces[0].pair_coeff[0]: '0 0 1 1 2.5 7': 6 fields (expected 'I J "
       "epsilon sigma' or 'I J epsilon sigma cutoff': two types, then numbers in J and m)"},
      {"pair_coeff: ['0 x 1 1']",
       "test.yaml:7:41: forces[0].pair_coeff[0]: '0 x 1 1': 'x' is not a type (expected a whole "
       "number in 0..255)"},
      {"pair_coeff: ['-1 0 1 1']",
       "test.yaml:7:41: forces[0].pair_coeff[0]: '-1 0 1 1': '-1' is not a type (expected a "
       "whole number in 0..255)"},
      {"pair_coeff: ['0 256 1 1']",
       "test.yaml:7:41: forces[0].pair_coeff[0]: '0 256 1 1': '256' is not a type (expected a "
       "whole number in 0..255)"},
      {"pair_coeff: ['0 0 1 1', '0 1 -0.5 1']",
       "test.yaml:7:52: forces[0].pair_coeff[1]: '0 1 -0.5 1': epsilon -0.5 J is negative "
       "(expected epsilon >= 0 J)"},
      {"pair_coeff: ['0 0 1 0']",
       "test.yaml:7:41: forces[0].pair_coeff[0]: '0 0 1 0': sigma 0 m (expected sigma > 0 m)"},
      {"pair_coeff: ['0 0 1 1 -2']",
       "test.yaml:7:41: forces[0].pair_coeff[0]: '0 0 1 1 -2': cutoff -2 m (expected cutoff > 0 "
       "m)"},
      {"pair_coeff: ['0 0 one 1']",
       "test.yaml:7:41: forces[0].pair_coeff[0]: '0 0 one 1': epsilon 'one' is not a number"},
      {"pair_coeff: ['0 0 1 1', '0 1 1 1', '1 0 2 1']",
       "test.yaml:7:63: forces[0].pair_coeff[2]: '1 0 2 1': the pair 0 1 is given again (first "
       "in row 1: '0 1 1 1')"},
      {"pair_coeff: ['0 0 1 1'], mix: lorentz",
       "test.yaml:7:58: forces[0].mix: 'lorentz' is not a mixing rule (expected geometric, "
       "arithmetic or none)"},
  };
  for (const auto& c : cases) {
    EXPECT_EQ(mixture_problems(c.entry), c.message) << c.entry;
  }
  // Rows cover the types 0..255 only.
  EXPECT_EQ(mixture_problems("pair_coeff: ['0 0 1 1'], epsilon: 1", "", "300"),
            "test.yaml:7:40: forces[0].pair_coeff: particle 2 has type 300 (expected types "
            "0..255 with pair_coeff, a table of every pair of types)");
  // A row's own cutoff that does not fit the periodic box is refused at that row.
  EXPECT_EQ(mixture_problems("pair_coeff: ['0 0 1 1', '1 1 1 1 4', '0 1 1 1']",
                             ", box: { min: [0, 0, 0], max: [8, 8, 8], periodic: [true, true, "
                             "true] }"),
            "test.yaml:7:52: forces[0].pair_coeff[1]: the largest cutoff, 4 m with skin 0.3 m "
            "does not fit the periodic box: its x side is 8 m (expected a side of at least 2 "
            "(cutoff + skin) = 8.6 m)");
  // Rows for types no particle has are kept for particles that never come:
  // the scene loads.
  EXPECT_EQ(mixture_problems("pair_coeff: ['0 0 1 1', '0 1 1 1', '1 1 1 1', '7 7 1 1']"),
            "(loaded without error)");
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
