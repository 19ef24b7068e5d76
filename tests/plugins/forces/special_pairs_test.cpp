// Special bonds in the pair loop (pdyn/special_bonds.hpp, PairForce in
// pdyn/pair.hpp): a Lennard-Jones law on chains of bonded particles with
// LAMMPS's weights. The forces with special bonds differ from the plain
// forces by exactly (w - 1) F_ij summed over the special pairs (worked out
// here pair by pair, apart from the loop), equal the all-pairs reference,
// and the energy and virial follow the same weights; the branching and the
// selecting loops agree; 1 to 4 threads give the same bits; clearing the
// special bonds gives the plain loop's bits back; and the Jacobians are
// the finite differences of the weighted forces.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>

#include "pdyn/host/assembly.hpp"
#include "pdyn/host/threads.hpp"
#include "pdyn/pair.hpp"
#include "pdyn/parallel.hpp"
#include "pdyn/special_bonds.hpp"
#include "pdyn/system.hpp"

namespace pdyn {
namespace {

// 4 (r^-12 - r^-6) within 2.5, with its slope for the Jacobians.
template <bool Select>
struct SpecialTestLaw {
  static constexpr bool evaluate_beyond_cutoff = Select;
  PairTerm operator()(double r2, std::int32_t, std::int32_t) const {
    const double r2inv = 1.0 / r2, r6inv = r2inv * r2inv * r2inv;
    return {4.0 * r6inv * (r6inv - 1.0), r6inv * (48.0 * r6inv - 24.0) * r2inv};
  }
  double force_over_r_slope(double r2, std::int32_t, std::int32_t) const {
    return -336.0 * std::pow(r2, -8.0) + 96.0 * std::pow(r2, -5.0);
  }
};
constexpr double kRc = 2.5, kSkin = 0.3;

// side^3 particles on a jittered cubic lattice of spacing 1.1, periodic or
// open.
std::unique_ptr<System> SpecialLattice(int side, bool periodic, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.05, 0.05);
  const Index n = side * side * side;
  Matrix3X x(3, n);
  Index k = 0;
  for (int a = 0; a < side; ++a)
    for (int b = 0; b < side; ++b)
      for (int c = 0; c < side; ++c)
        x.col(k++) =
            1.1 * Vec3(a + 0.5 + jitter(rng), b + 0.5 + jitter(rng), c + 0.5 + jitter(rng));
  auto sys = std::make_unique<System>();
  SystemAssembly(*sys).set_particles(x, Matrix3X::Zero(3, n), Eigen::VectorXd::Ones(n),
                                     std::vector<std::uint8_t>(static_cast<std::size_t>(n), 0));
  if (periodic) {
    Domain d;
    d.max = Vec3::Constant(side * 1.1);
    d.periodic = {true, true, true};
    SystemAssembly(*sys).set_domain(d);
  }
  return sys;
}

// Chains of 10 consecutive particles (neighbours along the lattice's
// fastest axis, and some across its rows) plus a ring of 6.
std::vector<IndexPair> SpecialChains(Index n) {
  std::vector<IndexPair> bonds;
  for (Index i = 0; i + 1 < n; ++i) {
    if ((i + 1) % 10 != 0) bonds.push_back({i, i + 1});
  }
  for (Index i = 0; i < 6; ++i) bonds.push_back({n - 6 + i, n - 6 + (i + 1) % 6});
  return bonds;
}

template <bool Select>
Matrix3X SpecialForces(const System& sys, const std::shared_ptr<const SpecialBonds>& special,
                       double* energy = nullptr, double* virial = nullptr) {
  PairForce<SpecialTestLaw<Select>> force({}, kRc, kSkin);
  force.set_special_bonds(special);
  Matrix3X f = Matrix3X::Constant(3, sys.size(), 0.125);
  force.add_forces(sys.view(), f);
  if (energy) *energy = *force.potential_energy(sys.view());
  if (virial) *virial = force.virial(sys.view());
  return f;
}

TEST(SpecialPairs, WeightedForcesDifferFromPlainOnesByTheSpecialPairsAlone) {
  for (const bool periodic : {false, true}) {
    SCOPED_TRACE(periodic ? "periodic" : "open");
    const auto sys = SpecialLattice(8, periodic, 5);
    const auto special = std::make_shared<const SpecialBonds>(
        special_bonds(sys->size(), SpecialChains(sys->size()), {0.0, 0.5, 0.25}));
    double u_plain = 0, w_plain = 0, u = 0, w = 0;
    const Matrix3X plain = SpecialForces<false>(*sys, nullptr, &u_plain, &w_plain);
    const Matrix3X weighted = SpecialForces<false>(*sys, special, &u, &w);
    // (w - 1) F_ij and (w - 1) U_ij of every special pair, by hand.
    Matrix3X change = Matrix3X::Zero(3, sys->size());
    double du = 0, dw = 0;
    int within = 0;
    const SpecialTestLaw<false> law;
    for (Index i = 0; i < sys->size(); ++i) {
      for (const Index j : special->partners_of(i)) {
        if (j < i) continue;
        const Vec3 d =
            sys->domain().minimum_image(sys->positions().col(i) - sys->positions().col(j));
        if (!(d.squaredNorm() < kRc * kRc)) continue;
        const PairTerm t = law(d.squaredNorm(), 0, 0);
        const double s = special->weight(i, j) - 1.0;
        change.col(i) += s * t.force_over_r * d;
        change.col(j) -= s * t.force_over_r * d;
        du += s * t.energy;
        dw += s * t.force_over_r * d.squaredNorm();
        ++within;
      }
    }
    EXPECT_GT(within, 500);  // 1-2, 1-3 and 1-4 pairs all within the cutoff
    const double scale = plain.cwiseAbs().maxCoeff();
    EXPECT_LE((weighted - plain - change).cwiseAbs().maxCoeff(), 1e-11 * scale);
    EXPECT_NEAR(u, u_plain + du, 1e-11 * std::abs(u_plain));
    EXPECT_NEAR(w, w_plain + dw, 1e-11 * std::abs(w_plain));
    // The all-pairs reference applies the same weights.
    PairForce<SpecialTestLaw<false>> force({}, kRc, kSkin);
    force.set_special_bonds(special);
    Matrix3X reference = Matrix3X::Constant(3, sys->size(), 0.125);
    const double u_ref = force.add_forces_all_pairs(sys->view(), reference);
    EXPECT_LE((weighted - reference).cwiseAbs().maxCoeff(), 1e-11 * scale);
    EXPECT_NEAR(u, u_ref, 1e-11 * std::abs(u));
    // The selecting loop gives the same forces to rounding.
    EXPECT_LE((SpecialForces<true>(*sys, special) - weighted).cwiseAbs().maxCoeff(), 1e-12 * scale);
  }
}

TEST(SpecialPairs, ClearingThemGivesThePlainLoopsBits) {
  const auto sys = SpecialLattice(8, true, 6);
  const auto special = std::make_shared<const SpecialBonds>(
      special_bonds(sys->size(), SpecialChains(sys->size()), {0.0, 1.0, 1.0}));
  PairForce<SpecialTestLaw<true>> force({}, kRc, kSkin);
  Matrix3X plain = Matrix3X::Zero(3, sys->size()), excluded = plain, again = plain;
  force.add_forces(sys->view(), plain);
  force.set_special_bonds(special);
  EXPECT_EQ(force.special_bonds(), special.get());
  force.add_forces(sys->view(), excluded);
  EXPECT_FALSE(excluded.cwiseEqual(plain).all());
  force.set_special_bonds(nullptr);
  EXPECT_EQ(force.special_bonds(), nullptr);
  force.add_forces(sys->view(), again);
  EXPECT_TRUE(again.cwiseEqual(plain).all());
  // An empty set (every weight 1) is no set.
  force.set_special_bonds(std::make_shared<const SpecialBonds>(
      special_bonds(sys->size(), SpecialChains(sys->size()), {1.0, 1.0, 1.0})));
  EXPECT_EQ(force.special_bonds(), nullptr);
}

// 21,952 particles: the threaded path.
TEST(SpecialPairs, OneToFourThreadsGiveTheSameBits) {
  const auto sys = SpecialLattice(28, true, 9);
  for (const std::array<double, 3> w :
       {std::array<double, 3>{0.0, 1.0, 1.0}, std::array<double, 3>{0.2, 0.5, 0.25}}) {
    const auto special = std::make_shared<const SpecialBonds>(
        special_bonds(sys->size(), SpecialChains(sys->size()), w));
    Matrix3X one_select, one_branch;
    for (const int threads : {1, 2, 3, 4}) {
      set_threads(threads);
      const Matrix3X select = SpecialForces<true>(*sys, special);
      const Matrix3X branch = SpecialForces<false>(*sys, special);
      if (threads == 1) {
        one_select = select;
        one_branch = branch;
      } else {
        EXPECT_TRUE(select.cwiseEqual(one_select).all()) << threads << " threads, w12 " << w[0];
        EXPECT_TRUE(branch.cwiseEqual(one_branch).all()) << threads << " threads, w12 " << w[0];
      }
    }
  }
  set_threads(available_threads());
}

// Dense df/dx of a small system, from add_jacobians.
class DenseSpecialSink : public JacobianSink {
 public:
  explicit DenseSpecialSink(Index n) : k(Eigen::MatrixXd::Zero(3 * n, 3 * n)) {}
  void add_dfdx(Index i, Index j, const Eigen::Matrix3d& block) override {
    k.block<3, 3>(3 * i, 3 * j) += block;
  }
  void add_dfdv(Index, Index, const Eigen::Matrix3d&) override {}
  Eigen::MatrixXd k;
};

TEST(SpecialPairs, JacobiansAreTheDerivativesOfTheWeightedForces) {
  const auto sys = SpecialLattice(3, false, 4);  // 27 particles
  const auto special = std::make_shared<const SpecialBonds>(
      special_bonds(sys->size(), SpecialChains(sys->size()), {0.3, 0.5, 0.25}));
  PairForce<SpecialTestLaw<false>> force({}, kRc, kSkin);
  force.set_special_bonds(special);
  DenseSpecialSink sink(sys->size());
  ASSERT_TRUE(force.add_jacobians(sys->view(), sink));
  const double h = 1e-6;
  double worst = 0.0;
  for (Index j = 0; j < sys->size(); ++j) {
    for (int a = 0; a < 3; ++a) {
      Matrix3X up = Matrix3X::Zero(3, sys->size()), down = up;
      sys->positions()(a, j) += h;
      force.add_forces(sys->view(), up);
      sys->positions()(a, j) -= 2 * h;
      force.add_forces(sys->view(), down);
      sys->positions()(a, j) += h;
      const Eigen::VectorXd column = (Eigen::Map<Eigen::VectorXd>(up.data(), up.size()) -
                                      Eigen::Map<Eigen::VectorXd>(down.data(), down.size())) /
                                     (2 * h);
      worst = std::max(worst, (sink.k.col(3 * j + a) - column).cwiseAbs().maxCoeff());
    }
  }
  EXPECT_LE(worst, 1e-5 * sink.k.cwiseAbs().maxCoeff());
}

}  // namespace
}  // namespace pdyn
