// A host's rebuild schedule for the shared neighbor lists
// (pdyn/kernel/neighbor_schedule.hpp), LAMMPS's neigh_modify every N delay D
// check yes|no: the steps at which lists rebuild, counted as LAMMPS's
// Neighbor::decide() counts them, once per step however often a list is
// updated in it; a replayed step not counted twice; the default schedule
// the per-call rule of NeighborList::update(); NeighborList's own Rebuild
// modes. And an MPI rank's ghosts (set_neighbor_ghosts): a pair of two
// ghosts is never listed, for half lists that drop them as they find pairs
// and full lists that drop them after; naming the ghosts again rebuilds the
// lists even where the count and the flags are the same (the host
// exchanged the particles, index i may be another one); and a list whose
// positions array was reallocated rebuilds for the new one.
#include <gtest/gtest.h>

#include <pdyn/kernel/neighbor_schedule.hpp>
#include <pdyn/neighbors.hpp>
#include <random>
#include <stdexcept>
#include <vector>

namespace pdyn {
namespace {

Domain PeriodicCube(double side) {
  Domain d;
  d.min = Vec3::Zero();
  d.max = Vec3::Constant(side);
  d.periodic = {true, true, true};
  return d;
}

Matrix3X Scattered(Index n, double side, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, side);
  Matrix3X x(3, n);
  for (Index i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) x(k, i) = u(rng);
  }
  return x;
}

TEST(NeighborListRebuild, ModesDecideWhatDisplacementDoesNot) {
  const Domain d = PeriodicCube(6.0);
  Matrix3X x = Scattered(100, 6.0, 3);
  NeighborList list(1.0, 0.4);
  using R = NeighborList::Rebuild;
  EXPECT_TRUE(list.update(x, d, nullptr, {R::IfForced}));  // never built: must
  x(0, 1) += 1.0;                                          // far beyond skin / 2
  EXPECT_FALSE(list.update(x, d, nullptr, {R::IfForced}));
  EXPECT_TRUE(list.update(x, d, nullptr, {R::IfMoved}));
  EXPECT_FALSE(list.update(x, d, nullptr, {R::IfMoved}));
  EXPECT_TRUE(list.update(x, d, nullptr, {R::Always}));                 // nothing moved
  EXPECT_TRUE(list.update(x.leftCols(50), d, nullptr, {R::IfForced}));  // N changed: must
  EXPECT_EQ(list.builds(), 4);
}

// The steps a list built at step 0 rebuilds at over `steps` steps, with
// `updates` updates per step, every particle moving `move` per step.
std::vector<int> RebuildSteps(const RebuildSchedule& schedule, int steps, int updates,
                              double move) {
  const Domain d = PeriodicCube(6.0);
  Matrix3X x = Scattered(100, 6.0, 7);
  SharedNeighborList shared(1.0, 0.4);
  shared.update(x, d);  // step 0's build, before any step begins
  std::int64_t builds = shared.list()->builds();
  std::vector<int> at;
  for (int s = 1; s <= steps; ++s) {
    begin_neighbor_step(x.data(), 0.1 * (s - 1), schedule);
    x.row(0).array() += move;
    for (int u = 0; u < updates; ++u) shared.update(x, d);
    if (shared.list()->builds() != builds) at.push_back(s);
    builds = shared.list()->builds();
  }
  begin_neighbor_step(x.data(), 0.0, RebuildSchedule{});  // forget it
  return at;
}

TEST(NeighborSchedule, CheckNoRebuildsEveryNStepsWhateverTheParticlesDo) {
  EXPECT_EQ(RebuildSteps({3, 0, false}, 10, 1, 0.0), (std::vector<int>{3, 6, 9}));
  // Moving half a cutoff per step changes nothing: the schedule decides.
  EXPECT_EQ(RebuildSteps({3, 0, false}, 10, 2, 0.5), (std::vector<int>{3, 6, 9}));
  // delay 4, every 3: the first step >= 4 steps after a build that is a multiple of 3.
  EXPECT_EQ(RebuildSteps({3, 4, false}, 13, 1, 0.0), (std::vector<int>{6, 12}));
}

TEST(NeighborSchedule, CheckYesRebuildsOnlyAtDecisionsAndOnlyIfMoved) {
  EXPECT_EQ(RebuildSteps({2, 0, true}, 8, 1, 0.0), (std::vector<int>{}));
  // 0.25 per step: beyond skin / 2 = 0.2 from the first step on, rebuilt
  // at the first decision after each build.
  EXPECT_EQ(RebuildSteps({2, 0, true}, 8, 3, 0.25), (std::vector<int>{2, 4, 6, 8}));
  EXPECT_EQ(RebuildSteps({1, 3, true}, 8, 1, 0.25), (std::vector<int>{3, 6}));
  // LAMMPS's default (every 1 delay 10 check yes) and pdyn's (every 1 delay 0).
  EXPECT_EQ(RebuildSteps({1, 10, true}, 25, 1, 0.25), (std::vector<int>{10, 20}));
  EXPECT_EQ(RebuildSteps({1, 0, true}, 4, 1, 0.25), (std::vector<int>{1, 2, 3, 4}));
}

TEST(NeighborSchedule, AReplayedStepIsCountedOnce) {
  const Domain d = PeriodicCube(6.0);
  Matrix3X x = Scattered(100, 6.0, 11);
  SharedNeighborList shared(1.0, 0.4);
  shared.update(x, d);
  const RebuildSchedule every2{2, 0, false};
  for (int replay = 0; replay < 3; ++replay) {
    begin_neighbor_step(x.data(), 0.0, every2);  // step 1, begun three times
    shared.update(x, d);
  }
  EXPECT_EQ(shared.list()->builds(), 1);
  begin_neighbor_step(x.data(), 0.1, every2);  // step 2: a decision
  shared.update(x, d);
  EXPECT_EQ(shared.list()->builds(), 2);
  begin_neighbor_step(x.data(), 0.0, RebuildSchedule{});
}

TEST(NeighborSchedule, WithoutOneListsKeepTheirRule) {
  // Another array's schedule does not reach these lists.
  Matrix3X other = Matrix3X::Zero(3, 4);
  begin_neighbor_step(other.data(), 0.0, RebuildSchedule{5, 0, false});
  EXPECT_EQ(RebuildSteps({}, 4, 1, 0.25), (std::vector<int>{1, 2, 3, 4}));
  begin_neighbor_step(other.data(), 0.0, RebuildSchedule{});
}

TEST(NeighborSchedule, RefusesBadCounts) {
  const double x[3] = {0, 0, 0};
  try {
    begin_neighbor_step(x, 0.0, RebuildSchedule{0, 0, true});
    ADD_FAILURE() << "accepted every = 0";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(),
                 "neighbor rebuild schedule: every = 0, delay = 0 (expected every >= 1, delay >= "
                 "0)");
  }
  EXPECT_THROW(begin_neighbor_step(x, 0.0, RebuildSchedule{1, -1, true}), std::invalid_argument);
}

// The ghosts' lists: a cube of this side (m), cutoff and skin.
constexpr double kSide = 8.0, kCutoff = 1.2, kSkin = 0.3;

// Row i of the brute-force list: every j within reach (nearest image),
// j > i for a half list, leaving out pairs of two ghosts.
std::vector<Index> BruteRow(const Matrix3X& x, const std::vector<std::uint8_t>& ghost, Index i,
                            NeighborList::Kind kind) {
  std::vector<Index> row;
  const Domain d = PeriodicCube(kSide);
  for (Index j = 0; j < x.cols(); ++j) {
    if (j == i || (kind == NeighborList::Kind::Half && j < i)) continue;
    if (ghost[static_cast<std::size_t>(i)] != 0 && ghost[static_cast<std::size_t>(j)] != 0)
      continue;
    if (d.minimum_image(x.col(j) - x.col(i)).norm() <= kCutoff + kSkin) row.push_back(j);
  }
  return row;
}

void ExpectBrute(const NeighborList& list, const Matrix3X& x,
                 const std::vector<std::uint8_t>& ghost, NeighborList::Kind kind) {
  ASSERT_EQ(list.size(), x.cols());
  for (Index i = 0; i < x.cols(); ++i) {
    const auto got = list.neighbors(i);
    ASSERT_EQ(std::vector<Index>(got.begin(), got.end()), BruteRow(x, ghost, i, kind)) << i;
  }
}

TEST(NeighborGhosts, PairsOfTwoGhostsAreNeverListed) {
  const Matrix3X x = Scattered(600, kSide, 5);
  std::vector<std::uint8_t> ghost(600);
  for (std::size_t i = 0; i < ghost.size(); ++i) ghost[i] = i % 3 == 0 ? 1 : 0;
  for (const auto kind : {NeighborList::Kind::Half, NeighborList::Kind::Full}) {
    set_neighbor_ghosts(x.data(), ghost.data(), x.cols());
    SharedNeighborList shared(kCutoff, kSkin, kind);
    ExpectBrute(shared.update(x, PeriodicCube(kSide)), x, ghost, kind);
    // Without ghosts the same list holds every pair again.
    set_neighbor_ghosts(x.data(), nullptr, 0);
    ExpectBrute(shared.update(x, PeriodicCube(kSide)), x, std::vector<std::uint8_t>(600, 0), kind);
  }
}

TEST(NeighborGhosts, GhostsNamedAgainRebuildTheListWithTheSameCountAndFlags) {
  Matrix3X x = Scattered(300, kSide, 6);
  x.col(1) = x.col(0) + Vec3(0.05, 0.0, 0.0);  // closer than skin / 2
  std::vector<std::uint8_t> ghost(300, 0);
  ghost[7] = 1;
  set_neighbor_ghosts(x.data(), ghost.data(), x.cols());
  SharedNeighborList shared(kCutoff, kSkin);
  shared.update(x, PeriodicCube(kSide));
  EXPECT_EQ(shared.list()->builds(), 1);
  // An exchange that put particles 0 and 1 in each other's place: no
  // index moved more than skin / 2, yet the list rebuilds because the
  // ghosts were named again.
  x.col(0).swap(x.col(1));
  set_neighbor_ghosts(x.data(), ghost.data(), x.cols());
  shared.update(x, PeriodicCube(kSide));
  EXPECT_EQ(shared.list()->builds(), 2);
  ExpectBrute(*shared.list(), x, ghost, NeighborList::Kind::Half);
  shared.update(x, PeriodicCube(kSide));  // nothing moved, nothing named: kept
  EXPECT_EQ(shared.list()->builds(), 2);
  set_neighbor_ghosts(x.data(), nullptr, 0);
}

TEST(NeighborGhosts, AListFollowsItsParticlesToAReallocatedArray) {
  // A System that reallocates its arrays (set_particles, as an MPI rank's
  // at each exchange) hands the force another array of the same count:
  // the list rebuilds for it, whatever the old array held.
  const Matrix3X first = Scattered(400, kSide, 7);
  SharedNeighborList shared(kCutoff, kSkin);
  shared.update(first, PeriodicCube(kSide));
  Matrix3X second = first;
  for (Index i = 0; i + 1 < second.cols(); i += 2) second.col(i).swap(second.col(i + 1));
  ExpectBrute(shared.update(second, PeriodicCube(kSide)), second, std::vector<std::uint8_t>(400, 0),
              NeighborList::Kind::Half);
  const Matrix3X third = Scattered(350, kSide, 8);
  ExpectBrute(shared.update(third, PeriodicCube(kSide)), third, std::vector<std::uint8_t>(350, 0),
              NeighborList::Kind::Half);
}

}  // namespace
}  // namespace pdyn
