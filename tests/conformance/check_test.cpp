// `pdyn check` and the conformance kit: every shipped plugin passes, every
// broken fixture fails, naming the check it breaks.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "pdyn/conformance.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

const std::string kBroken = std::string(PDYN_FIXTURE_DIR) + "/broken";

TEST(Check, EveryShippedPluginPasses) {
  ASSERT_FALSE(test::shipped_plugins().plugins().empty());
  for (const auto& r : test::shipped_plugins().plugins()) {
    const auto res = test::pdyn({"check", r.descriptor->name});
    EXPECT_EQ(res.status, 0) << r.descriptor->name << ":\n" << res.out << res.err;
    EXPECT_NE(res.out.find("all checks passed"), std::string::npos) << res.out;
  }
}

TEST(Check, ShippedPluginsPassInProcess) {
  for (const auto& r : test::shipped_plugins().plugins()) {
    const auto results = conformance::run_checks(*r.descriptor, {.seed = 7});
    EXPECT_TRUE(conformance::all_passed(results)) << r.descriptor->name << ":\n"
                                                  << conformance::table(results);
  }
}

struct BrokenCase {
  const char* plugin;
  const char* failed_check;
};

class CheckBroken : public testing::TestWithParam<BrokenCase> {};

TEST_P(CheckBroken, FailsNamingTheCheck) {
  const auto res = test::pdyn({"check", GetParam().plugin, "--plugin-path", kBroken});
  EXPECT_EQ(res.status, 1) << res.out << res.err;
  // The table row and the summary both name the failed check.
  EXPECT_NE(res.out.find(std::string(GetParam().failed_check) + " "), std::string::npos) << res.out;
  EXPECT_NE(res.out.find("failed: "), std::string::npos) << res.out;
  const auto summary = res.out.substr(res.out.find("failed: "));
  EXPECT_NE(summary.find(GetParam().failed_check), std::string::npos) << res.out;
}

INSTANTIATE_TEST_SUITE_P(Fixtures, CheckBroken,
                         testing::Values(BrokenCase{"one_sided", "force.net_force_zero"},
                                         BrokenCase{"one_sided", "force.net_torque_zero"},
                                         BrokenCase{"bad_potential", "force.gradient_of_potential"},
                                         BrokenCase{"fake_rk4", "solver.convergence_order"},
                                         BrokenCase{"leaky_plane", "collider.obstacle_found"},
                                         BrokenCase{"misdrawn_plane", "collider.shape"},
                                         BrokenCase{"shared_scratch", "threads.two_systems"},
                                         BrokenCase{"bad_default", "params.bad_rejected"}),
                         [](const auto& param_info) {
                           return std::string(param_info.param.plugin) + "_" +
                                  std::to_string(param_info.index);
                         });

TEST(Check, MeasuresTheFakeSolversRealOrder) {
  const auto res = test::pdyn({"check", "fake_rk4", "--plugin-path", kBroken});
  // Euler's order is 1, measured within 0.1; the bound on |measured - 4| is 0.3.
  std::istringstream lines(res.out);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("solver.convergence_order", 0) != 0) continue;
    std::istringstream row(line);
    std::string name, verdict;
    double measured = 0, bound = 0;
    row >> name >> verdict >> measured >> bound;
    EXPECT_EQ(verdict, "FAIL");
    EXPECT_NEAR(measured, 1.0, 0.1);
    EXPECT_EQ(bound, 0.3);
    return;
  }
  FAIL() << "no convergence row:\n" << res.out;
}

TEST(Check, AcceptsALibraryPath) {
  const auto res = test::pdyn({"check", kBroken + "/pdyn_solver_fake_rk4.so"});
  EXPECT_EQ(res.status, 1) << res.out << res.err;
}

TEST(Check, UnknownPluginIsBadInputWithSuggestion) {
  const auto res = test::pdyn({"check", "sprin"});
  EXPECT_EQ(res.status, 2);
  EXPECT_NE(res.err.find("did you mean 'spring'?"), std::string::npos) << res.err;
}

TEST(Check, UnloadableLibraryIsPluginFault) {
  const auto res =
      test::pdyn({"check", std::string(PDYN_FIXTURE_DIR) + "/abi/pdyn_force_abi_broken.so"});
  EXPECT_EQ(res.status, 3) << res.out << res.err;
  EXPECT_NE(res.err.find("pdyn_force_abi_broken.so"), std::string::npos) << res.err;
}

TEST(Check, WritesJUnit) {
  const auto dir = test::temp_dir("check_junit");
  const auto file = dir / "report.xml";
  const auto res =
      test::pdyn({"check", "one_sided", "--plugin-path", kBroken, "--junit", file.string()});
  EXPECT_EQ(res.status, 1);
  std::ifstream in(file);
  const std::string xml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(xml.find("<testsuite name=\"pdyn.check.one_sided\""), std::string::npos) << xml;
  EXPECT_NE(xml.find("name=\"force.net_force_zero\">\n    <failure"), std::string::npos) << xml;
}

TEST(Check, SampleParamsFillRequiredIndexPairs) {
  const auto* spring = test::shipped_plugins().find(PluginKind::Force, "spring");
  ASSERT_NE(spring, nullptr);
  const Params p = conformance::sample_params(*spring->descriptor, 6);
  ASSERT_TRUE(p.has("pairs"));
  for (const auto& pair : p.pairs("pairs")) {
    EXPECT_NE(pair[0], pair[1]);
    EXPECT_LT(pair[1], 6);
  }
  EXPECT_EQ(p.real("ks"), 1.0);
  EXPECT_FALSE(p.has("rest"));  // optional without default: left out
}

}  // namespace
}  // namespace pdyn
