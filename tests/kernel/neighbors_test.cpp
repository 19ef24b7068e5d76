// The neighbor list (pdyn/neighbors.hpp) against brute force. After every
// update() the list holds each pair closer than the cutoff (all N^2 / 2
// pairs checked, nearest image along periodic axes) and nothing that was
// farther than cutoff + skin at its build; it rebuilds exactly when Verlet's
// rule says (a particle moved more than skin / 2); it is bit-identical for 1
// to 4 threads; bad sizes and boxes are refused with their numbers; NaN
// particles get no neighbors. Open space, periodic and mixed boxes, boxes of
// 1, 2 and 3 cells per axis, particles on the faces, half and full lists,
// member masks.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <iostream>
#include <limits>
#include <pdyn/host/threads.hpp>
#include <pdyn/neighbors.hpp>
#include <pdyn/parallel.hpp>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace pdyn {
namespace {

using Kind = NeighborList::Kind;
using Mask = std::vector<std::uint8_t>;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

Domain Box(Vec3 min, Vec3 max, std::array<bool, 3> periodic) {
  Domain d;
  d.min = min;
  d.max = max;
  d.periodic = periodic;
  return d;
}

// n particles uniform in [lo, hi).
Matrix3X Uniform(Index n, const Vec3& lo, const Vec3& hi, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Matrix3X x(3, n);
  for (Index i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) x(k, i) = lo[k] + (hi[k] - lo[k]) * u(rng);
  }
  return x;
}

Mask RandomMask(Index n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  Mask m(static_cast<std::size_t>(n));
  for (auto& b : m) b = static_cast<std::uint8_t>(rng() % 2);
  return m;
}

bool Listed(const Mask* mask, const Matrix3X& x, Index i) {
  return (!mask || (*mask)[static_cast<std::size_t>(i)]) && x.col(i).allFinite();
}

// Whether j is in particle i's row (rows are ascending).
bool Has(const NeighborList& list, Index i, Index j) {
  const auto row = list.neighbors(i);
  return std::binary_search(row.begin(), row.end(), j);
}

// Checks the list against brute force: `now` are the positions of the last
// update(), `built` those of the last build. The list holds exactly the pairs
// of listed particles within reach at the build (under i < j for a half
// list, under both for a full one), and so every pair within the cutoff now;
// rows are ascending and duplicate-free.
void ExpectHolds(const NeighborList& list, const Matrix3X& now, const Matrix3X& built,
                 const Domain& d, const Mask* mask = nullptr) {
  const Index n = now.cols();
  ASSERT_EQ(list.size(), n);
  ASSERT_EQ(list.offsets().size(), static_cast<std::size_t>(n) + 1);
  ASSERT_EQ(list.offsets().front(), 0);
  ASSERT_EQ(list.offsets().back(), static_cast<Index>(list.indices().size()));
  const bool full = list.kind() == Kind::Full;
  Index entries = 0;
  for (Index i = 0; i < n; ++i) {
    const auto row = list.neighbors(i);
    if (!Listed(mask, built, i)) {
      ASSERT_TRUE(row.empty()) << "particle " << i << " is not listed";
    }
    for (std::size_t a = 0; a < row.size(); ++a) {
      const Index j = row[a];
      ASSERT_TRUE(j >= 0 && j < n && j != i) << i << " lists " << j;
      if (!full) {
        ASSERT_GT(j, i);
      } else {
        ASSERT_TRUE(Has(list, j, i)) << i << " lists " << j << " but not the other way";
      }
      if (a > 0) {
        ASSERT_LT(row[a - 1], j) << "row " << i << " not ascending";
      }
      ASSERT_TRUE(Listed(mask, built, j)) << i << " lists unlisted " << j;
      const double r = d.minimum_image(built.col(j) - built.col(i)).norm();
      ASSERT_LE(r, list.reach() * (1 + 1e-12)) << "pair " << i << ", " << j << " beyond reach";
      ++entries;
    }
  }
  ASSERT_EQ(list.pair_count(), full ? entries / 2 : entries);
  // Within reach at the build (but for rounding), within cutoff now: listed.
  const double reach = list.reach() * (1 - 1e-12);
  for (Index i = 0; i < n; ++i) {
    for (Index j = i + 1; j < n; ++j) {
      if (Listed(mask, built, i) && Listed(mask, built, j) &&
          d.minimum_image(built.col(j) - built.col(i)).norm() < reach) {
        ASSERT_TRUE(Has(list, i, j)) << "pair " << i << ", " << j << " within reach at the build";
      }
      if (Listed(mask, now, i) && Listed(mask, now, j) &&
          d.minimum_image(now.col(j) - now.col(i)).norm() < list.cutoff()) {
        ASSERT_TRUE(Has(list, i, j)) << "pair " << i << ", " << j << " within cutoff now";
      }
    }
  }
}

// Builds from scratch and checks, for both kinds, with and without a mask.
void ExpectBuildHolds(const Matrix3X& x, const Domain& d, double cutoff, double skin) {
  const Mask mask = RandomMask(x.cols(), 7);
  for (const Kind kind : {Kind::Half, Kind::Full}) {
    for (const Mask* m : {static_cast<const Mask*>(nullptr), &mask}) {
      SCOPED_TRACE(testing::Message()
                   << (kind == Kind::Half ? "half" : "full") << (m ? ", masked" : ""));
      NeighborList list(cutoff, skin, kind);
      ASSERT_TRUE(list.update(x, d, m));
      ExpectHolds(list, x, x, d, m);
      EXPECT_EQ(list.builds(), 1);
      EXPECT_GT(list.pair_count(), 0) << "no pair to check";
    }
  }
}

TEST(Domain, MinimumImageAndWrap) {
  const Domain d = Box({-1, 0, 0}, {3, 10, 10}, {true, false, true});
  EXPECT_EQ(d.length(), Vec3(4, 10, 10));
  EXPECT_EQ(d.minimum_image({3.5, 7, -9}), Vec3(-0.5, 7, 1));
  EXPECT_EQ(d.minimum_image({-1.5, -7, 4}), Vec3(-1.5, -7, 4));
  EXPECT_EQ(d.wrap({3, 12, 10}), Vec3(-1, 12, 0));  // max is min's image
  EXPECT_EQ(d.wrap({-1.5, -3, -0.25}), Vec3(2.5, -3, 9.75));
  EXPECT_EQ(d.wrap({11.25, 0, 25}), Vec3(-0.75, 0, 5));
  const Vec3 inside(0.1 + 0.2, 0.3, 9.999999999999998);
  EXPECT_EQ(d.wrap(inside), inside);            // bit for bit
  const Vec3 w = d.wrap({-1e-17, 0, -1e-300});  // rounds to max: becomes min
  EXPECT_GE(w[0], -1.0);
  EXPECT_LT(w[0], 3.0);
  EXPECT_GE(w[2], 0.0);
  EXPECT_LT(w[2], 10.0);
  EXPECT_TRUE(std::isnan(d.wrap({kNaN, 0, 0})[0]));
  const Domain open;  // unbounded: nothing changes
  EXPECT_EQ(open.minimum_image({1e9, -2, 3}), Vec3(1e9, -2, 3));
  EXPECT_EQ(open.wrap({1e9, -2, 3}), Vec3(1e9, -2, 3));
}

TEST(NeighborList, OpenSpaceMatchesBruteForce) {
  ExpectBuildHolds(Uniform(1500, {-3, 0, 2}, {7, 10, 12}, 1), Domain{}, 1.0, 0.2);
  // A flat sheet and a line: one cell across the thin axes.
  Matrix3X sheet = Uniform(800, {0, 0, 0}, {8, 8, 0}, 2);
  ExpectBuildHolds(sheet, Domain{}, 0.6, 0.1);
  ExpectBuildHolds(Uniform(400, {0, 5, 5}, {40, 5, 5}, 3), Domain{}, 0.3, 0.05);
  // The bounds of an open axis in the domain are not used.
  ExpectBuildHolds(Uniform(500, {-5, -5, -5}, {5, 5, 5}, 4), Box({0, 0, 0}, {1, 1, 1}, {}), 1.0,
                   0.5);
}

TEST(NeighborList, SparseSystemCapsTheCells) {
  // A "galaxy": clusters 1e6 m apart plus outliers up to 1e12 m away. A grid
  // of reach-sized cells over the bounding box would need ~1e34 cells.
  std::mt19937_64 rng(5);
  std::normal_distribution<double> g(0.0, 1.0);
  Matrix3X x(3, 1200);
  for (Index i = 0; i < x.cols(); ++i) {
    const double centre = 1e6 * static_cast<double>(i % 5);
    for (int k = 0; k < 3; ++k) x(k, i) = centre + 2.0 * g(rng);
  }
  x.col(0) << 1e12, -1e12, 3;
  x.col(1) << -1e12, 1e12, 3;
  ExpectBuildHolds(x, Domain{}, 1.0, 0.25);
  // Coordinates whose differences overflow to inf: no crash, nothing wrong.
  x.col(2) << 1.7e308, 0, 0;
  x.col(3) << -1.7e308, 0, 0;
  x.col(4) << 1.7e308, 0, 1e-3;
  NeighborList list(1.0, 0.25, Kind::Full);
  list.update(x, Domain{});
  ExpectHolds(list, x, x, Domain{});
  EXPECT_EQ(std::vector<Index>(list.neighbors(2).begin(), list.neighbors(2).end()),
            std::vector<Index>{4});
}

TEST(NeighborList, PeriodicMatchesBruteForce) {
  // cutoff + skin = 1.5: a box of 7 has 4 cells per axis.
  ExpectBuildHolds(Uniform(1500, {-2, -2, -2}, {5, 5, 5}, 6),
                   Box({-2, -2, -2}, {5, 5, 5}, {true, true, true}), 1.2, 0.3);
  // Positions not yet wrapped into the box, up to two lengths outside.
  ExpectBuildHolds(Uniform(1200, {-16, -14, -12}, {19, 21, 23}, 7),
                   Box({-2, 0, 2}, {5, 7, 9}, {true, true, true}), 1.2, 0.3);
}

TEST(NeighborList, MixedPeriodicMatchesBruteForce) {
  // A slab periodic in x and y, open in z (particles above and below it).
  ExpectBuildHolds(Uniform(1200, {0, 0, -3}, {6, 6, 9}, 8),
                   Box({0, 0, 0}, {6, 6, 4}, {true, true, false}), 1.0, 0.25);
  // Periodic in z only.
  ExpectBuildHolds(Uniform(1000, {-4, -4, 0}, {4, 4, 5}, 9),
                   Box({0, 0, 0}, {1, 1, 5}, {false, false, true}), 1.0, 0.25);
}

TEST(NeighborList, OneTwoAndThreeCellsPerAxis) {
  // reach = 1.5, cells of side >= 0.75, and periodic lengths 3 (2 reach: 3
  // cells), 3.5 (4 cells), 3.8 (5 cells, the fewest that need no fold) and
  // 4.6 (6 cells), in every combination of axes: a pair across an axis of
  // fewer than 5 cells, where one cell is a neighbor both ways round, must be
  // found once, at its nearest image.
  const double lengths[] = {3.0, 3.5, 3.8, 4.6};
  std::uint64_t seed = 10;
  for (const double lx : lengths) {
    for (const double ly : lengths) {
      for (const double lz : lengths) {
        SCOPED_TRACE(testing::Message() << "box " << lx << " x " << ly << " x " << lz);
        const Vec3 hi(lx, ly, lz);
        ExpectBuildHolds(Uniform(150, Vec3::Zero(), hi, ++seed),
                         Box(Vec3::Zero(), hi, {true, true, true}), 1.2, 0.3);
      }
    }
  }
  // One cell along a periodic axis, open elsewhere.
  ExpectBuildHolds(Uniform(300, {0, 0, 0}, {3, 8, 8}, 40),
                   Box({0, 0, 0}, {3, 1, 1}, {true, false, false}), 1.2, 0.3);
}

TEST(NeighborList, ParticlesOnTheFaces) {
  // A lattice of spacing 0.5 from face to face of a periodic 4 m box:
  // coordinates 0 and 4 both occur, and 4 is 0's image (distance 0). No
  // lattice distance (0.5 sqrt(k)) equals the cutoff 1.1 or reach 1.4.
  std::vector<Vec3> points;
  for (int a = 0; a <= 8; ++a) {
    for (int b = 0; b <= 8; ++b) {
      for (int c = 0; c <= 8; ++c) points.emplace_back(0.5 * a, 0.5 * b, 0.5 * c);
    }
  }
  Matrix3X x(3, static_cast<Index>(points.size()));
  for (Index i = 0; i < x.cols(); ++i) x.col(i) = points[static_cast<std::size_t>(i)];
  ExpectBuildHolds(x, Box({0, 0, 0}, {4, 4, 4}, {true, true, true}), 1.1, 0.3);
  ExpectBuildHolds(x, Box({0, 0, 0}, {4, 4, 4}, {true, false, true}), 1.1, 0.3);
  ExpectBuildHolds(x, Domain{}, 1.1, 0.3);
  // A particle on the max face sees its neighbors across the min face.
  Matrix3X two(3, 2);
  two << 4.0, 0.3, 0, 0, 0, 0;
  NeighborList list(1.1, 0.3);
  list.update(two, Box({0, 0, 0}, {4, 4, 4}, {true, true, true}));
  EXPECT_EQ(list.pair_count(), 1);
}

// Random small moves, wrapped back into the box as a host would: after every
// update() the list holds, and it rebuilds exactly when some particle has
// moved more than skin / 2 (nearest image) since the last build.
void ExpectUpdatesHold(const Domain& d, const Vec3& lo, const Vec3& hi, Kind kind,
                       const Mask* mask) {
  const double cutoff = 1.0, skin = 0.3;
  Matrix3X x = Uniform(500, lo, hi, 50), built = x;
  NeighborList list(cutoff, skin, kind);
  ASSERT_TRUE(list.update(x, d, mask));
  std::mt19937_64 rng(51);
  std::uniform_real_distribution<double> step(-0.02, 0.02);
  std::int64_t expected_builds = 1;
  for (int s = 0; s < 100; ++s) {
    for (Index i = 0; i < x.cols(); ++i) {
      x.col(i) = d.wrap(x.col(i) + Vec3(step(rng), step(rng), step(rng)));
    }
    double moved = 0;
    for (Index i = 0; i < x.cols(); ++i) {
      if (!mask || (*mask)[static_cast<std::size_t>(i)]) {
        moved = std::max(moved, d.minimum_image(x.col(i) - built.col(i)).norm());
      }
    }
    const bool rebuild = moved > skin / 2;
    ASSERT_EQ(list.update(x, d, mask), rebuild) << "step " << s << ", moved " << moved;
    if (rebuild) {
      built = x;
      ++expected_builds;
    }
    ASSERT_NO_FATAL_FAILURE(ExpectHolds(list, x, built, d, mask)) << "step " << s;
  }
  EXPECT_EQ(list.builds(), expected_builds);
  // A step of 0.02 per coordinate needs several steps to reach 0.15: the
  // skin saves most builds, and some are needed.
  EXPECT_GT(expected_builds, 5);
  EXPECT_LT(expected_builds, 60);
}

TEST(NeighborList, UpdatesKeepEveryPairWithinCutoff) {
  const Mask mask = RandomMask(500, 52);
  const Domain periodic = Box({0, 0, 0}, {8, 8, 8}, {true, true, true});
  const Domain mixed = Box({0, 0, 0}, {8, 8, 8}, {false, true, true});
  {
    SCOPED_TRACE("periodic, half");
    ExpectUpdatesHold(periodic, {0, 0, 0}, {8, 8, 8}, Kind::Half, nullptr);
  }
  {
    SCOPED_TRACE("periodic, full, masked");
    ExpectUpdatesHold(periodic, {0, 0, 0}, {8, 8, 8}, Kind::Full, &mask);
  }
  {
    SCOPED_TRACE("mixed, half, masked");
    ExpectUpdatesHold(mixed, {0, 0, 0}, {8, 8, 8}, Kind::Half, &mask);
  }
  {
    SCOPED_TRACE("open, full");
    ExpectUpdatesHold(Domain{}, {0, 0, 0}, {8, 8, 8}, Kind::Full, nullptr);
  }
}

// A barostat's box: every step the particles move a little and the box
// and positions dilate about the centre, by a factor that swings either way
// (so that a particle is wrapped in one box and measured in another). The
// list must hold every pair within the cutoff of the current box at every
// step, without rebuilding at every step.
TEST(NeighborList, AResizedBoxKeepsEveryPairWithinCutoff) {
  const double cutoff = 1.0, skin = 0.3;
  Domain d = Box({0, 0, 0}, {8, 8, 8}, {true, true, true});
  Matrix3X x = Uniform(500, {0, 0, 0}, {8, 8, 8}, 81);
  // The shared list is the one pair forces use; it keeps a resized box's
  // list (a plain NeighborList rebuilds for any other domain).
  SharedNeighborList shared(cutoff, skin);
  shared.update(x, d);
  const NeighborList& list = *shared.list();
  std::mt19937_64 rng(82);
  std::uniform_real_distribution<double> step(-0.01, 0.01);
  const int steps = 200;
  for (int s = 0; s < steps; ++s) {
    const double f = 1.0 + 0.003 * std::sin(0.2 * s);
    const Vec3 centre = 0.5 * (d.min + d.max);
    Domain next = d;
    next.min = (d.min - centre) * f + centre;
    next.max = (d.max - centre) * f + centre;
    for (Index i = 0; i < x.cols(); ++i) {
      const Vec3 moved = (x.col(i) - centre) * f + centre + Vec3(step(rng), step(rng), step(rng));
      x.col(i) = next.wrap(moved);
    }
    d = next;
    shared.update(x, d);
    for (Index i = 0; i < x.cols(); ++i) {
      for (Index j = i + 1; j < x.cols(); ++j) {
        if (d.minimum_image(x.col(j) - x.col(i)).norm() < cutoff) {
          ASSERT_TRUE(Has(list, i, j)) << "step " << s << ": pair " << i << ", " << j;
        }
      }
    }
  }
  EXPECT_TRUE(NeighborList::resizes(Box({0, 0, 0}, {8, 8, 8}, {true, true, true}), d));
  EXPECT_FALSE(NeighborList::resizes(d, Box({0, 0, 0}, {8, 8, 8}, {true, true, false})));
  std::cout << "resized box: " << list.builds() << " builds in " << steps << " steps\n";
  EXPECT_GT(list.builds(), 2);
  EXPECT_LT(list.builds(), steps / 2);

  // One face moving in while no particle moves: only the images come
  // closer, which Verlet's displacement rule alone would never see.
  Domain shrinking = Box({0, 0, 0}, {8, 8, 8}, {true, true, true});
  Matrix3X still = Uniform(500, {0, 0, 0}, {7.5, 8, 8}, 83);
  SharedNeighborList shared_faces(cutoff, skin);
  shared_faces.update(still, shrinking);
  const NeighborList& faces = *shared_faces.list();
  for (int s = 0; s < 50; ++s) {
    shrinking.max[0] -= 0.01;
    shared_faces.update(still, shrinking);
    for (Index i = 0; i < still.cols(); ++i) {
      for (Index j = i + 1; j < still.cols(); ++j) {
        if (shrinking.minimum_image(still.col(j) - still.col(i)).norm() < cutoff) {
          ASSERT_TRUE(Has(faces, i, j)) << "face step " << s << ": pair " << i << ", " << j;
        }
      }
    }
  }
  EXPECT_GT(faces.builds(), 1);
  // A plain list rebuilds in any other box.
  NeighborList plain(cutoff, skin);
  ASSERT_TRUE(plain.update(still, shrinking));
  shrinking.max[0] -= 0.001;
  EXPECT_TRUE(plain.update(still, shrinking));
}

TEST(NeighborList, RebuildsWhenAndOnlyWhenNeeded) {
  const double skin = 0.4;
  const Domain d = Box({0, 0, 0}, {6, 6, 6}, {true, true, true});
  Matrix3X x = Uniform(200, {0, 0, 0}, {6, 6, 6}, 60);
  NeighborList list(1.0, skin);
  EXPECT_EQ(list.size(), 0);
  EXPECT_EQ(list.builds(), 0);
  EXPECT_TRUE(list.update(x, d));   // never built
  EXPECT_FALSE(list.update(x, d));  // nothing moved
  x(0, 5) += 0.49 * skin;
  x(1, 6) -= 0.49 * skin;
  EXPECT_FALSE(list.update(x, d));  // below skin / 2
  x(0, 5) += 0.02 * skin;           // 0.51 skin from the build
  EXPECT_TRUE(list.update(x, d));
  EXPECT_FALSE(list.update(x, d));
  // Wrapped by a whole box length: the nearest image has not moved.
  x(2, 7) += 6.0;
  EXPECT_FALSE(list.update(x, d));
  EXPECT_EQ(list.builds(), 2);
  // The domain, the particle count or the mask changed: rebuilt.
  const Domain bigger = Box({0, 0, 0}, {6, 6, 7}, {true, true, true});
  EXPECT_TRUE(list.update(x, bigger));
  EXPECT_TRUE(list.update(x.leftCols(150), bigger));
  Mask mask(150, 1);
  EXPECT_TRUE(list.update(x.leftCols(150), bigger, &mask));
  EXPECT_FALSE(list.update(x.leftCols(150), bigger, &mask));
  mask[3] = 0;
  EXPECT_TRUE(list.update(x.leftCols(150), bigger, &mask));
  EXPECT_TRUE(list.update(x.leftCols(150), bigger));
  EXPECT_EQ(list.builds(), 7);
  list.build(x.leftCols(150), bigger);  // forced
  EXPECT_EQ(list.builds(), 8);
  // skin = 0: any move rebuilds, none does not.
  NeighborList tight(1.0, 0.0);
  EXPECT_TRUE(tight.update(x, d));
  EXPECT_FALSE(tight.update(x, d));
  x(0, 0) = std::nextafter(x(0, 0), 10.0);
  EXPECT_TRUE(tight.update(x, d));
  ExpectHolds(tight, x, x, d);
}

TEST(NeighborList, BitIdenticalForOneToFourThreads) {
  // 20 000 particles at the Lennard-Jones melt density 0.8442 (random, not a
  // lattice), rc = 2.5, skin 0.3: ~40 half-list neighbors each, far above
  // kParallelMinElements, so every parallel loop splits.
  const Index n = 20000;
  const double L = std::cbrt(static_cast<double>(n) / 0.8442);
  const Domain d = Box({0, 0, 0}, {L, L, L}, {true, true, true});
  const Matrix3X x = Uniform(n, {0, 0, 0}, {L, L, L}, 70);
  const Mask mask = RandomMask(n, 71);
  ASSERT_GT(n, kParallelMinElements);
  const int saved = max_threads();
  for (const Kind kind : {Kind::Half, Kind::Full}) {
    for (const Mask* m : {static_cast<const Mask*>(nullptr), &mask}) {
      std::vector<Index> offsets, indices;
      for (const int threads : {1, 2, 3, 4}) {
        set_threads(threads);
        ASSERT_EQ(max_threads(), threads);
        NeighborList list(2.5, 0.3, kind);
        list.update(x, d, m);
        if (threads == 1) {
          offsets.assign(list.offsets().begin(), list.offsets().end());
          indices.assign(list.indices().begin(), list.indices().end());
          EXPECT_GT(list.pair_count(), (m ? 5 : 30) * n);
          continue;
        }
        EXPECT_TRUE(std::equal(offsets.begin(), offsets.end(), list.offsets().begin(),
                               list.offsets().end()))
            << threads << " threads";
        EXPECT_TRUE(std::equal(indices.begin(), indices.end(), list.indices().begin(),
                               list.indices().end()))
            << threads << " threads";
      }
    }
  }
  set_threads(saved);
}

std::string Message(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(NeighborList, RefusesBadSizesWithTheirNumbers) {
  EXPECT_EQ(Message([] { (void)NeighborList(0.0, 0.3); }),
            "neighbor list: cutoff must be finite and > 0 m, got 0");
  EXPECT_EQ(Message([] { (void)NeighborList(-1.5, 0.3); }),
            "neighbor list: cutoff must be finite and > 0 m, got -1.5");
  EXPECT_EQ(Message([] { (void)NeighborList(kNaN, 0.3); }),
            "neighbor list: cutoff must be finite and > 0 m, got nan");
  EXPECT_EQ(Message([] { (void)NeighborList(kInf, 0.3); }),
            "neighbor list: cutoff must be finite and > 0 m, got inf");
  EXPECT_EQ(Message([] { (void)NeighborList(1.0, -0.25); }),
            "neighbor list: skin must be finite and >= 0 m, got -0.25");
  EXPECT_EQ(Message([] { (void)NeighborList(1.0, kInf, Kind::Full); }),
            "neighbor list: skin must be finite and >= 0 m, got inf");
  EXPECT_EQ(Message([] { (void)NeighborList(1.0, 0.0); }), "(no error)");
}

TEST(NeighborList, RefusesATooSmallPeriodicBox) {
  const Matrix3X x = Uniform(10, {0, 0, 0}, {4, 4, 4}, 80);
  NeighborList list(2.0, 0.5);
  EXPECT_EQ(Message([&] {
              list.update(x, Box({0, 0, 0}, {6, 4.5, 6}, {true, true, true}));
            }),
            "neighbor list: periodic axis y is 4.5 m long, less than 2 (cutoff + skin) = 5 m: a "
            "particle would meet two images of one neighbor");
  EXPECT_EQ(Message([&] {
              list.build(x, Box({0, 0, -1}, {6, 6, 2}, {false, false, true}));
            }),
            "neighbor list: periodic axis z is 3 m long, less than 2 (cutoff + skin) = 5 m: a "
            "particle would meet two images of one neighbor");
  // Open axes may be as thin as they like; exactly 2 (cutoff + skin) is enough.
  EXPECT_EQ(Message([&] {
              list.update(x, Box({0, 0, 0}, {5, 1, 0}, {true, false, false}));
            }),
            "(no error)");
  EXPECT_EQ(Message([&] {
              list.update(x, Box({0, 0, 0}, {kInf, 6, 6}, {true, false, false}));
            }),
            "neighbor list: periodic axis x needs finite bounds with max > min, got min = 0 m, "
            "max = inf m");
  EXPECT_EQ(Message([&] {
              list.update(x, Box({0, 7, 0}, {6, 1, 6}, {false, true, false}));
            }),
            "neighbor list: periodic axis y needs finite bounds with max > min, got min = 7 m, "
            "max = 1 m");
  const Mask short_mask(9, 1);
  EXPECT_EQ(Message([&] { list.update(x, Domain{}, &short_mask); }),
            "neighbor list: the member mask has 9 entries for 10 particles");
  // A refused call leaves the list as it was.
  EXPECT_EQ(list.builds(), 1);
  EXPECT_EQ(list.size(), 10);
}

TEST(NeighborList, NonFiniteParticlesGetNoNeighbors) {
  const Domain d = Box({0, 0, 0}, {5, 5, 5}, {true, true, false});
  Matrix3X x = Uniform(400, {0, 0, 0}, {5, 5, 5}, 90);
  const Vec3 near = x.col(10);
  x.col(3) << kNaN, 1, 1;
  x.col(4) << kInf, 0, 0;
  x.col(5) << 1, 1, -kInf;
  x.col(6) << kNaN, kNaN, kNaN;
  x.col(11) = near;  // at distance 0 from particle 10
  for (const Kind kind : {Kind::Half, Kind::Full}) {
    NeighborList list(1.0, 0.25, kind);
    ASSERT_TRUE(list.update(x, d));
    ExpectHolds(list, x, x, d);
    for (const Index i : {3, 4, 5, 6}) EXPECT_TRUE(list.neighbors(i).empty()) << i;
    // Still not finite: nothing to do. Finite again: listed again.
    EXPECT_FALSE(list.update(x, d));
    Matrix3X y = x;
    y.col(3) = near;
    EXPECT_TRUE(list.update(y, d));
    ExpectHolds(list, y, y, d);
    EXPECT_FALSE(list.neighbors(kind == Kind::Half ? 3 : 10).empty());
    // Finite, then not: unlisted.
    EXPECT_TRUE(list.update(x, d));
    ExpectHolds(list, x, x, d);
  }
  // Nothing finite at all.
  const Matrix3X nans = Matrix3X::Constant(3, 50, kNaN);
  NeighborList list(1.0, 0.25);
  EXPECT_TRUE(list.update(nans, Domain{}));
  EXPECT_EQ(list.pair_count(), 0);
  EXPECT_EQ(list.size(), 50);
}

TEST(NeighborList, EmptyAndSingle) {
  NeighborList list(1.0, 0.1, Kind::Full);
  EXPECT_TRUE(list.update(Matrix3X(3, 0), Domain{}));
  EXPECT_EQ(list.size(), 0);
  EXPECT_EQ(list.offsets().size(), 1u);
  EXPECT_FALSE(list.update(Matrix3X(3, 0), Domain{}));
  EXPECT_TRUE(list.update(Matrix3X::Zero(3, 1), Domain{}));
  EXPECT_TRUE(list.neighbors(0).empty());
}

}  // namespace
}  // namespace pdyn
