// pdyn::resolve, the one place parameter values meet their specs: defaults,
// required, types, finiteness, bounds, not-zero vectors, unknown names.
#include "pdyn/host/resolve.hpp"

#include <gtest/gtest.h>

#include <limits>

namespace pdyn {
namespace {

std::vector<ParamSpec> specs() {
  return {param::real("ks", 100.0, "N/m", "stiffness").at_least(0),
          param::real("dt", 0.01, "s", "step").greater_than(0).at_most(1),
          param::integer("every", 1, "frames").at_least(0),
          param::vec3("normal", Vec3(0, 0, 1), "", "normal").not_zero(),
          param::optional("rest", ParamType::RealList, "m", "rest lengths").at_least(0),
          param::required("pairs", ParamType::IndexPairs, "", "springs"),
          param::optional("constants", ParamType::NamedReals, "", "constants").at_most(10)};
}

Params with_pairs() {
  Params p;
  p.set("pairs", std::vector<IndexPair>{{0, 1}});
  return p;
}

TEST(Resolve, FillsEveryDefaultAndKeepsGivenValues) {
  Params given = with_pairs();
  given.set("ks", 5.0);
  const Resolved r = resolve(specs(), given);
  ASSERT_TRUE(r.ok()) << r.problems[0].message;
  EXPECT_EQ(r.params.real("ks"), 5.0);
  EXPECT_EQ(r.params.real("dt"), 0.01);
  EXPECT_EQ(r.params.integer("every"), 1);
  EXPECT_EQ(r.params.vec3("normal"), Vec3(0, 0, 1));
  EXPECT_FALSE(r.params.has("rest"));  // optional without default: not set
  EXPECT_EQ(r.params.pairs("pairs").size(), 1u);
}

TEST(Resolve, AMissingRequiredParameterIsAProblem) {
  const Resolved r = resolve(specs(), Params{});
  ASSERT_EQ(r.problems.size(), 1u);
  EXPECT_EQ(r.problems[0].kind, ParamProblem::Kind::Missing);
  EXPECT_EQ(r.problems[0].param, "pairs");
  EXPECT_EQ(r.problems[0].message,
            "missing required parameter 'pairs' (expected a list of particle index pairs [[i, "
            "j], ...]: springs)");
}

TEST(Resolve, BoundsAreCheckedOnNumbersVectorsListsAndNamedReals) {
  Params given = with_pairs();
  given.set("ks", -1.0);
  given.set("dt", 0.0);  // exclusive minimum
  given.set("every", std::int64_t{-2});
  given.set("rest", std::vector<double>{0.1, -0.5, 0.2, -1.0});
  given.set("constants", NamedReals{{"a", 1.0}, {"b", 11.0}});
  const Resolved r = resolve(specs(), given);
  ASSERT_EQ(r.problems.size(), 6u);
  EXPECT_EQ(r.problems[0].message,
            "parameter 'ks': -1 is out of range (expected a number >= 0 in N/m)");
  EXPECT_EQ(r.problems[1].message,
            "parameter 'dt': 0 is out of range (expected a number in (0, 1] in s)");
  EXPECT_EQ(r.problems[2].message,
            "parameter 'every': -2 is out of range (expected a whole number >= 0)");
  EXPECT_EQ(r.problems[3].element, (std::vector<std::size_t>{1}));
  EXPECT_EQ(r.problems[3].value, -0.5);
  EXPECT_EQ(r.problems[4].element, (std::vector<std::size_t>{3}));
  EXPECT_EQ(r.problems[5].key, "b");
  EXPECT_EQ(r.problems[5].value, 11.0);
  for (const auto& p : r.problems) EXPECT_EQ(p.kind, ParamProblem::Kind::OutOfRange);
}

TEST(Resolve, AZeroOrNonFiniteVectorIsRefusedAtItsFirstBadComponent) {
  Params given = with_pairs();
  given.set("normal", Vec3(0, 0, 0));
  Resolved r = resolve(specs(), given);
  ASSERT_EQ(r.problems.size(), 1u);
  EXPECT_EQ(r.problems[0].kind, ParamProblem::Kind::ZeroVector);
  given.set("normal", Vec3(1, std::numeric_limits<double>::infinity(), std::nan("")));
  r = resolve(specs(), given);
  ASSERT_EQ(r.problems.size(), 1u);  // one per vector
  EXPECT_EQ(r.problems[0].kind, ParamProblem::Kind::NotFinite);
  EXPECT_EQ(r.problems[0].element, (std::vector<std::size_t>{1}));
}

TEST(Resolve, AWrongTypeAndAnUnknownNameAreProblems) {
  Params given = with_pairs();
  given.set("ks", std::string("stiff"));
  given.set("kss", 3.0);
  const Resolved r = resolve(specs(), given);
  ASSERT_EQ(r.problems.size(), 2u);
  EXPECT_EQ(r.problems[0].kind, ParamProblem::Kind::WrongType);
  EXPECT_EQ(r.problems[0].param, "ks");
  EXPECT_EQ(r.problems[1].kind, ParamProblem::Kind::Unknown);
  EXPECT_EQ(r.problems[1].param, "kss");
}

TEST(Resolve, ADefaultOutsideItsOwnBoundsIsReportedLikeAGivenValue) {
  const std::vector<ParamSpec> bad = {param::real("ks", -5.0, "N/m", "").at_least(0)};
  const Resolved r = resolve(bad, Params{});
  ASSERT_EQ(r.problems.size(), 1u);
  EXPECT_EQ(r.problems[0].kind, ParamProblem::Kind::OutOfRange);
}

}  // namespace
}  // namespace pdyn
