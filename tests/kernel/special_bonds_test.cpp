// The special partners of a bond graph (pdyn/special_bonds.hpp), against
// LAMMPS's rule worked out by hand: in a chain the partners one, two and
// three bonds along are 1-2, 1-3 and 1-4, the fourth is an ordinary pair;
// in rings of 3 to 6 each pair takes its shortest way round; a branch point
// counts its arms' beads; repeated bonds count once; partners whose weight
// is 1 are not listed; SpecialRows drops the weight-0 pairs of a neighbor
// list and marks the others; every bad input's exact message.
#include "pdyn/special_bonds.hpp"

#include <gtest/gtest.h>

#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace pdyn {
namespace {

// Particle i's special partners as partner -> order (1: 1-2, 2: 1-3, 3: 1-4).
std::map<Index, int> PartnersOf(const SpecialBonds& s, Index i) {
  std::map<Index, int> out;
  const auto row = s.partners_of(i);
  for (std::size_t k = 0; k < row.size(); ++k) {
    out[row[k]] = s.order[static_cast<std::size_t>(s.offsets[static_cast<std::size_t>(i)]) + k];
  }
  return out;
}

std::vector<IndexPair> Ring(Index n) {
  std::vector<IndexPair> bonds;
  for (Index i = 0; i < n; ++i) bonds.push_back({i, (i + 1) % n});
  return bonds;
}

constexpr std::array<double, 3> kAllWeighted{0.0, 0.5, 0.25};

TEST(SpecialBonds, AChainHasItsOneTwoOneThreeAndOneFourPartners) {
  // 0 - 1 - 2 - 3 - 4 - 5
  const std::vector<IndexPair> bonds = {{0, 1}, {1, 2}, {2, 3}, {3, 4}, {4, 5}};
  const SpecialBonds s = special_bonds(6, bonds, kAllWeighted);
  EXPECT_EQ(PartnersOf(s, 0), (std::map<Index, int>{{1, 1}, {2, 2}, {3, 3}}));
  EXPECT_EQ(PartnersOf(s, 2), (std::map<Index, int>{{0, 2}, {1, 1}, {3, 1}, {4, 2}, {5, 3}}));
  EXPECT_EQ(s.weight(0, 1), 0.0);
  EXPECT_EQ(s.weight(0, 2), 0.5);
  EXPECT_EQ(s.weight(0, 3), 0.25);
  EXPECT_EQ(s.weight(0, 4), 1.0);  // four bonds apart: an ordinary pair
  EXPECT_EQ(s.weight(3, 0), 0.25);
  EXPECT_EQ(s.weight(7, 0), 1.0);  // beyond the particles it was built for
}

TEST(SpecialBonds, RingPairsTakeTheirShortestWayRound) {
  // A triangle: every pair is bonded.
  EXPECT_EQ(PartnersOf(special_bonds(3, Ring(3), kAllWeighted), 0),
            (std::map<Index, int>{{1, 1}, {2, 1}}));
  // A square: the opposite corner is two bonds either way.
  EXPECT_EQ(PartnersOf(special_bonds(4, Ring(4), kAllWeighted), 0),
            (std::map<Index, int>{{1, 1}, {2, 2}, {3, 1}}));
  // A pentagon: 2 and 3 are two bonds away, each by its own side.
  EXPECT_EQ(PartnersOf(special_bonds(5, Ring(5), kAllWeighted), 0),
            (std::map<Index, int>{{1, 1}, {2, 2}, {3, 2}, {4, 1}}));
  // A hexagon (benzene's ring): the para position is 1-4.
  EXPECT_EQ(PartnersOf(special_bonds(6, Ring(6), kAllWeighted), 0),
            (std::map<Index, int>{{1, 1}, {2, 2}, {3, 3}, {4, 2}, {5, 1}}));
}

TEST(SpecialBonds, ABranchPointCountsEachArmAndRepeatsCountOnce) {
  // A star: 0 at the centre of arms 0-1-4, 0-2-5, 0-3; bond 0-1 given twice
  // and once reversed.
  const std::vector<IndexPair> bonds = {{0, 1}, {1, 0}, {0, 1}, {0, 2}, {0, 3}, {1, 4}, {2, 5}};
  const SpecialBonds s = special_bonds(6, bonds, kAllWeighted);
  EXPECT_EQ(PartnersOf(s, 1), (std::map<Index, int>{{0, 1}, {2, 2}, {3, 2}, {4, 1}, {5, 3}}));
  EXPECT_EQ(PartnersOf(s, 4), (std::map<Index, int>{{0, 2}, {1, 1}, {2, 3}, {3, 3}}));
  EXPECT_EQ(PartnersOf(s, 3), (std::map<Index, int>{{0, 1}, {1, 2}, {2, 2}, {4, 3}, {5, 3}}));
}

TEST(SpecialBonds, PartnersOfWeightOneAreNotListed) {
  const std::vector<IndexPair> chain = {{0, 1}, {1, 2}, {2, 3}};
  // LAMMPS's `special_bonds fene`: only the bonded pairs are special.
  const SpecialBonds fene = special_bonds(4, chain, {0.0, 1.0, 1.0});
  EXPECT_EQ(PartnersOf(fene, 1), (std::map<Index, int>{{0, 1}, {2, 1}}));
  EXPECT_FALSE(fene.scales());
  EXPECT_TRUE(special_bonds(4, chain, kAllWeighted).scales());
  EXPECT_TRUE(special_bonds(4, chain, {1.0, 1.0, 1.0}).empty());
  EXPECT_TRUE(special_bonds(4, {}, kAllWeighted).empty());
  EXPECT_EQ(special_bonds(4, {}, kAllWeighted).size(), 4);
}

TEST(SpecialBonds, BadInputIsRefusedWithItsReason) {
  auto message = [](Index n, std::vector<IndexPair> bonds, std::array<double, 3> w) {
    try {
      special_bonds(n, bonds, w);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  EXPECT_EQ(message(3, {{0, 1}, {1, 3}}, kAllWeighted),
            "bond 1 joins particles 1 and 3 (expected indices in 0 .. 2)");
  EXPECT_EQ(message(3, {{2, 2}}, kAllWeighted),
            "bond 0 joins particle 2 to itself (expected two particles)");
  EXPECT_EQ(message(3, {}, {0.0, 1.5, 1.0}), "the 1-3 weight is 1.5 (expected 0 to 1)");
  EXPECT_EQ(message(3, {}, {0.0, 1.0, -0.5}), "the 1-4 weight is -0.5 (expected 0 to 1)");
}

TEST(SpecialBonds, RowsLeaveOutTheExcludedPairsAndMarkTheScaledOnes) {
  // Half-list rows of 5 particles: 0: 1 2 3 4, 1: 2 4, 2: 3, 3: 4, 4: none.
  const std::vector<Index> offsets = {0, 4, 6, 7, 8, 8};
  const std::vector<Index> indices = {1, 2, 3, 4, 2, 4, 3, 4};
  // The chain 0 - 1 - 2 - 3, particle 4 alone.
  const SpecialBonds s =
      special_bonds(5, std::vector<IndexPair>{{0, 1}, {1, 2}, {2, 3}}, {0.0, 0.5, 1.0});
  SpecialRows rows;
  rows.build(offsets, indices, s);
  const std::vector<Index> got_offsets(rows.offsets(), rows.offsets() + 6);
  EXPECT_EQ(got_offsets, (std::vector<Index>{0, 3, 4, 4, 5, 5}));
  const std::vector<Index> got(rows.indices(), rows.indices() + 5);
  EXPECT_EQ(got, (std::vector<Index>{2, 3, 4, 4, 4}));  // 0-1, 1-2 and 2-3 left out
  const std::vector<int> which(rows.which(), rows.which() + 5);
  EXPECT_EQ(which, (std::vector<int>{2, 0, 0, 0, 0}));  // 0-2 is 1-3; 0-3 (1-4) has weight 1
  EXPECT_EQ(rows.scale(), (std::array<double, 4>{1.0, 0.0, 0.5, 1.0}));
}

}  // namespace
}  // namespace pdyn
