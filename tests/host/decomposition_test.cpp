// The box cut among ranks (pdyn/host/decomposition.hpp; issue 43): the
// automatic grid has the least subdomain surface, ownership and bounds()
// agree bit for bit, and ghost_ranks() lists exactly the subdomains within
// reach, checked against the distance from a point to each subdomain's
// box over every periodic image.
#include "pdyn/host/decomposition.hpp"

#include <gtest/gtest.h>

#include <random>

#include "pdyn/error.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

// The call throws Error with exactly `message`.
template <class F>
void expect_decomposition_error(F&& call, const std::string& message) {
  try {
    call();
    ADD_FAILURE() << "no error; expected: " << message;
  } catch (const ::pdyn::Error& e) {
    EXPECT_EQ(std::string(e.what()), message);
  }
}

TEST(Decomposition, TheAutomaticGridHasTheLeastSurface) {
  EXPECT_EQ(choose_rank_grid(1, Vec3(1, 1, 1)).n, (std::array<int, 3>{1, 1, 1}));
  // A cube: two ranks cut once (ties go to x), four cut twice, eight thrice.
  EXPECT_EQ(choose_rank_grid(2, Vec3(1, 1, 1)).n, (std::array<int, 3>{2, 1, 1}));
  EXPECT_EQ(choose_rank_grid(4, Vec3(1, 1, 1)).n, (std::array<int, 3>{2, 2, 1}));
  EXPECT_EQ(choose_rank_grid(8, Vec3(1, 1, 1)).n, (std::array<int, 3>{2, 2, 2}));
  // A prime count can only be cut one way, along the longest axis.
  EXPECT_EQ(choose_rank_grid(3, Vec3(1, 1, 5)).n, (std::array<int, 3>{1, 1, 3}));
  // A flat cloth's region (thin along z) is cut in its plane.
  EXPECT_EQ(choose_rank_grid(4, Vec3(10, 10, 0.01)).n, (std::array<int, 3>{2, 2, 1}));
  EXPECT_EQ(choose_rank_grid(6, Vec3(30, 10, 10)).n, (std::array<int, 3>{6, 1, 1}));
}

TEST(Decomposition, BadGridsAreRefusedWithTheirValue) {
  EXPECT_EQ(parse_rank_grid("2,1,2", 4).n, (std::array<int, 3>{2, 1, 2}));
  EXPECT_EQ(parse_rank_grid("1x3x1", 3).n, (std::array<int, 3>{1, 3, 1}));
  expect_decomposition_error([] { parse_rank_grid("2,2", 4); },
                             "--grid 2,2: not a grid (expected three positive integers, NX,NY,NZ)");
  expect_decomposition_error(
      [] { parse_rank_grid("2,0,2", 0); },
      "--grid 2,0,2: not a grid (expected three positive integers, NX,NY,NZ)");
  expect_decomposition_error(
      [] { parse_rank_grid("2,2,2 ", 8); },
      "--grid 2,2,2 : not a grid (expected three positive integers, NX,NY,NZ)");
  expect_decomposition_error(
      [] { parse_rank_grid("2,2,2", 4); },
      "--grid 2,2,2: 8 subdomains for 4 ranks (expected the product to be 4)");
  expect_decomposition_error([] { choose_rank_grid(0, Vec3(1, 1, 1)); },
                             "0 ranks: no grid (expected at least 1)");
  expect_decomposition_error(
      [] {
        Decomposition(RankGrid{}, Vec3(0, 0, 0), Vec3(1, 0, 1), {false, false, false}, 0.1);
      },
      "region [0, 0] m along axis 1: cannot be cut (expected finite, lo < hi)");
}

// Distance from x to the box [lo, hi], nearest image along periodic axes
// (every combination of images, not axis by axis).
double distance_to(const Vec3& x, const std::array<Vec3, 2>& box, const Vec3& length,
                   const std::array<bool, 3>& periodic) {
  double best = 1e300;
  for (int i = -1; i <= 1; ++i) {
    for (int j = -1; j <= 1; ++j) {
      for (int k = -1; k <= 1; ++k) {
        const std::array<int, 3> s{i, j, k};
        double d2 = 0;
        bool ok = true;
        for (int a = 0; a < 3; ++a) {
          if (!periodic[static_cast<std::size_t>(a)] && s[static_cast<std::size_t>(a)] != 0)
            ok = false;
          const double c = x[a] + s[static_cast<std::size_t>(a)] * length[a];
          const double g = c < box[0][a] ? box[0][a] - c : (c > box[1][a] ? c - box[1][a] : 0.0);
          d2 += g * g;
        }
        if (ok) best = std::min(best, std::sqrt(d2));
      }
    }
  }
  return best;
}

TEST(Decomposition, OwnersAndGhostRanksMatchTheGeometry) {
  const Vec3 lo(-1, 0, 2), hi(9, 6, 5);
  for (const auto& [grid, periodic] :
       {std::pair{RankGrid{{4, 3, 2}}, std::array<bool, 3>{true, true, false}},
        std::pair{RankGrid{{2, 1, 3}}, std::array<bool, 3>{true, false, true}},
        std::pair{RankGrid{{5, 1, 1}}, std::array<bool, 3>{false, false, false}}}) {
    const Decomposition d(grid, lo, hi, periodic, 1.3);
    std::mt19937_64 g(3);
    std::vector<int> ghosts;
    for (int n = 0; n < 2000; ++n) {
      Vec3 x;
      // Along open axes a quarter of the points have left the region (by up
      // to half its length): they stay owned by the edge cells, and their
      // ghosts are measured to those.
      const double spread = n % 4 == 0 ? 2.0 : 1.0;
      for (int a = 0; a < 3; ++a) {
        const double u = static_cast<double>(g() >> 11) * 0x1p-53;
        const double s = periodic[static_cast<std::size_t>(a)] ? 1.0 : spread;
        x[a] = lo[a] + (hi[a] - lo[a]) * (0.5 + s * (u - 0.5));
      }
      const int owner = d.owner(x);
      const auto b = d.bounds(owner);
      ASSERT_TRUE((x.array() >= b[0].array()).all() && (x.array() < b[1].array()).all())
          << x.transpose();
      ghosts.clear();
      d.ghost_ranks(x, owner, ghosts);
      std::vector<int> expected;
      for (int r = 0; r < grid.ranks(); ++r) {
        if (r != owner && distance_to(x, d.bounds(r), hi - lo, periodic) <= 1.3)
          expected.push_back(r);
      }
      ASSERT_EQ(ghosts, expected) << x.transpose();
    }
  }
}

}  // namespace
}  // namespace pdyn
