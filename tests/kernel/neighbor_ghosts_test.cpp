// The ghosts of an MPI rank in the shared neighbor lists (set_neighbor_ghosts,
// pdyn/kernel/neighbor_schedule.hpp): a pair of two ghosts is never listed
// (it gives no owned particle a force), for half lists that drop them as
// they find pairs and full lists that drop them after; naming the ghosts
// again rebuilds the lists even where the count and the flags are the same
// (the host exchanged the particles, index i may be another one); and a
// list whose positions array was reallocated rebuilds for the new one.
#include <gtest/gtest.h>

#include <pdyn/kernel/neighbor_schedule.hpp>
#include <pdyn/neighbors.hpp>
#include <random>
#include <vector>

namespace pdyn {
namespace {

constexpr double kSide = 8.0, kCutoff = 1.2, kSkin = 0.3;

Domain PeriodicCube() {
  Domain d;
  d.max = Vec3::Constant(kSide);
  d.periodic = {true, true, true};
  return d;
}

Matrix3X Scattered(Index n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, kSide);
  Matrix3X x(3, n);
  for (Index i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) x(k, i) = u(rng);
  }
  return x;
}

// Row i of the brute-force list: every j within reach (nearest image),
// j > i for a half list, leaving out pairs of two ghosts.
std::vector<Index> BruteRow(const Matrix3X& x, const std::vector<std::uint8_t>& ghost, Index i,
                            NeighborList::Kind kind) {
  std::vector<Index> row;
  const Domain d = PeriodicCube();
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
  const Matrix3X x = Scattered(600, 5);
  std::vector<std::uint8_t> ghost(600);
  for (std::size_t i = 0; i < ghost.size(); ++i) ghost[i] = i % 3 == 0 ? 1 : 0;
  for (const auto kind : {NeighborList::Kind::Half, NeighborList::Kind::Full}) {
    set_neighbor_ghosts(x.data(), ghost.data(), x.cols());
    SharedNeighborList shared(kCutoff, kSkin, kind);
    ExpectBrute(shared.update(x, PeriodicCube()), x, ghost, kind);
    // Without ghosts the same list holds every pair again.
    set_neighbor_ghosts(x.data(), nullptr, 0);
    ExpectBrute(shared.update(x, PeriodicCube()), x, std::vector<std::uint8_t>(600, 0), kind);
  }
}

TEST(NeighborGhosts, GhostsNamedAgainRebuildTheListWithTheSameCountAndFlags) {
  Matrix3X x = Scattered(300, 6);
  x.col(1) = x.col(0) + Vec3(0.05, 0.0, 0.0);  // closer than skin / 2
  std::vector<std::uint8_t> ghost(300, 0);
  ghost[7] = 1;
  set_neighbor_ghosts(x.data(), ghost.data(), x.cols());
  SharedNeighborList shared(kCutoff, kSkin);
  shared.update(x, PeriodicCube());
  EXPECT_EQ(shared.list()->builds(), 1);
  // An exchange that put particles 0 and 1 in each other's place: no
  // index moved more than skin / 2, yet the list rebuilds because the
  // ghosts were named again.
  x.col(0).swap(x.col(1));
  set_neighbor_ghosts(x.data(), ghost.data(), x.cols());
  shared.update(x, PeriodicCube());
  EXPECT_EQ(shared.list()->builds(), 2);
  ExpectBrute(*shared.list(), x, ghost, NeighborList::Kind::Half);
  shared.update(x, PeriodicCube());  // nothing moved, nothing named: kept
  EXPECT_EQ(shared.list()->builds(), 2);
  set_neighbor_ghosts(x.data(), nullptr, 0);
}

TEST(NeighborGhosts, AListFollowsItsParticlesToAReallocatedArray) {
  // A System that reallocates its arrays (set_particles, as an MPI rank's
  // at each exchange) hands the force another array of the same count:
  // the list rebuilds for it, whatever the old array held.
  const Matrix3X first = Scattered(400, 7);
  SharedNeighborList shared(kCutoff, kSkin);
  shared.update(first, PeriodicCube());
  Matrix3X second = first;
  for (Index i = 0; i + 1 < second.cols(); i += 2) second.col(i).swap(second.col(i + 1));
  ExpectBrute(shared.update(second, PeriodicCube()), second, std::vector<std::uint8_t>(400, 0),
              NeighborList::Kind::Half);
  const Matrix3X third = Scattered(350, 8);
  ExpectBrute(shared.update(third, PeriodicCube()), third, std::vector<std::uint8_t>(350, 0),
              NeighborList::Kind::Half);
}

}  // namespace
}  // namespace pdyn
