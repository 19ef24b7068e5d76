// The conformance kit's constraint checks (conformance/src/constraints.cpp)
// on the fixtures of tests/fixtures/rod_and_pin.cpp: the correct rod and
// moving pin pass every check, and each broken one fails exactly its own
// check and passes every other, on several seeds; `pdyn check` says so too.
#include <gtest/gtest.h>

#include <map>
#include <string>
#include <vector>

#include "pdyn/conformance.hpp"
#include "pdyn/host/registry.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace constraint_check_test {

// Every check a constraint plugin gets, in the report's order.
const std::vector<std::string> kChecks = {"descriptor.complete",
                                          "construct.defaults",
                                          "constraint.pattern",
                                          "constraint.deterministic",
                                          "constraint.read_only",
                                          "constraint.finite_on_degenerate",
                                          "constraint.satisfied_at_creation",
                                          "constraint.jacobian",
                                          "constraint.rate",
                                          "constraint.bias",
                                          "params.bad_rejected",
                                          "threads.two_systems"};

// Each broken fixture (in broken/) and the one check it must fail.
const std::map<std::string, std::string> kOwnCheck = {
    {"rod_bad_jacobian", "constraint.jacobian"},
    {"rod_no_bias", "constraint.bias"},
    {"pin_no_rate", "constraint.rate"},
    {"rod_unsatisfied", "constraint.satisfied_at_creation"}};

std::string fixture_dir(const std::string& folder) {
  return std::string(PDYN_FIXTURE_DIR) + "/" + folder;
}

// The kit's report on FOLDER/pdyn_constraint_NAME.so, run in this process.
std::vector<conformance::CheckResult> report(const std::string& folder, const std::string& name,
                                             std::uint64_t seed) {
  PluginRegistry registry;
  const std::string lib = fixture_dir(folder) + "/pdyn_constraint_" + name + ".so";
  if (!registry.load_library(lib)) {
    ADD_FAILURE() << lib << ": " << registry.faults().back().message;
    return {};
  }
  const PluginDescriptor& d = *registry.plugins().back().descriptor;
  EXPECT_EQ(d.kind, PluginKind::Constraint) << lib;
  EXPECT_EQ(d.name, name) << lib;
  return conformance::run_checks(d, {.seed = seed});
}

// The report's check names, in order.
std::vector<std::string> names_of(const std::vector<conformance::CheckResult>& results) {
  std::vector<std::string> names;
  for (const auto& r : results) names.push_back(r.name);
  return names;
}

TEST(ConstraintCheck, CorrectFixturesPassEveryCheck) {
  for (const std::string name : {"rod", "moving_pin"}) {
    for (const std::uint64_t seed : {1u, 2u, 3u}) {
      const auto results = report("constraints", name, seed);
      EXPECT_EQ(names_of(results), kChecks) << name << ":\n" << conformance::table(results);
      for (const auto& r : results) {
        EXPECT_EQ(r.verdict, conformance::Verdict::Pass)
            << name << " (seed " << seed << "): " << r.name << ": " << r.detail << "\n"
            << conformance::table(results);
      }
    }
  }
}

TEST(ConstraintCheck, EachBrokenFixtureFailsOnlyItsOwnCheck) {
  for (const auto& [name, own] : kOwnCheck) {
    for (const std::uint64_t seed : {1u, 2u, 3u}) {
      const auto results = report("broken", name, seed);
      EXPECT_EQ(names_of(results), kChecks) << name << ":\n" << conformance::table(results);
      for (const auto& r : results) {
        const auto expected =
            r.name == own ? conformance::Verdict::Fail : conformance::Verdict::Pass;
        EXPECT_EQ(r.verdict, expected)
            << name << " (seed " << seed << "): " << r.name << ": " << r.detail << "\n"
            << conformance::table(results);
      }
    }
  }
}

// A failed derivative check says by how much: far beyond its bound, not
// at its edge.
TEST(ConstraintCheck, BrokenDerivativesMissByFar) {
  for (const auto& [name, own] : kOwnCheck) {
    const auto results = report("broken", name, 1);
    for (const auto& r : results) {
      if (r.name != own) continue;
      EXPECT_GT(r.measured, 1e3 * r.bound) << name << ": " << r.name << ": " << r.detail;
    }
  }
}

// Through `pdyn check` (isolated in a child process): exit 0 for the
// correct ones, 1 naming the check for the broken ones.
TEST(ConstraintCheck, PdynCheckReportsTheFixtures) {
  for (const std::string name : {"rod", "moving_pin"}) {
    const auto res = test::pdyn({"check", name, "--plugin-path", fixture_dir("constraints")});
    EXPECT_EQ(res.status, 0) << res.out << res.err;
    EXPECT_NE(res.out.find("pdyn check: constraint " + name), std::string::npos) << res.out;
    EXPECT_NE(res.out.find("all checks passed"), std::string::npos) << res.out;
  }
  for (const auto& [name, own] : kOwnCheck) {
    const auto res = test::pdyn({"check", name, "--plugin-path", fixture_dir("broken")});
    EXPECT_EQ(res.status, 1) << res.out << res.err;
    const auto at = res.out.find("check(s) failed: ");
    ASSERT_NE(at, std::string::npos) << res.out;
    EXPECT_EQ(res.out.substr(at), "check(s) failed: " + own + "\n") << res.out;
  }
}

}  // namespace constraint_check_test
}  // namespace pdyn
