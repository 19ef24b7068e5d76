// `pdyn check` and the conformance kit: every shipped plugin passes, every
// broken fixture fails, naming the check it breaks; the pair forces pass
// the pair.* checks, and each broken pair force fails only its own.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <map>
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
                                         BrokenCase{"leaky_thermostat", "solver.extended_energy"},
                                         BrokenCase{"leaky_plane", "collider.obstacle_found"},
                                         BrokenCase{"misdrawn_plane", "collider.shape"},
                                         BrokenCase{"shared_scratch", "threads.two_systems"},
                                         BrokenCase{"bad_default", "params.bad_rejected"},
                                         BrokenCase{"not_periodic", "force.periodic_invariant"},
                                         BrokenCase{"misdeclared_law", "force.linear_law"},
                                         BrokenCase{"bad_pair_gradient", "pair.gradient"},
                                         BrokenCase{"lopsided_pair", "pair.newton_third_law"},
                                         BrokenCase{"stale_pair_list", "pair.matches_brute_force"},
                                         BrokenCase{"jumping_pair", "pair.continuous_at_cutoff"},
                                         BrokenCase{"unscaled_pair", "pair.special_bonds"},
                                         BrokenCase{"bond_one_sided", "bonded.third_law"},
                                         BrokenCase{"bond_bad_energy", "bonded.gradient"},
                                         BrokenCase{"bond_bad_hessian", "bonded.jacobian_exact"},
                                         BrokenCase{"bond_indefinite", "bonded.jacobian_definite"},
                                         BrokenCase{"bond_drops_term", "bonded.matches_terms"}),
                         [](const auto& param_info) {
                           return std::string(param_info.param.plugin) + "_" +
                                  std::to_string(param_info.index);
                         });

// The verdicts of the pair.* rows of `pdyn check`'s table, by check name.
std::map<std::string, std::string> pair_verdicts(const std::string& table) {
  std::map<std::string, std::string> out;
  std::istringstream lines(table);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("pair.", 0) != 0) continue;
    std::istringstream row(line);
    std::string name, verdict;
    row >> name >> verdict;
    out[name] = verdict;
  }
  return out;
}

TEST(Check, EachBrokenPairForceFailsOnlyItsOwnPairCheck) {
  const std::map<std::string, std::string> own = {{"bad_pair_gradient", "pair.gradient"},
                                                  {"lopsided_pair", "pair.newton_third_law"},
                                                  {"stale_pair_list", "pair.matches_brute_force"},
                                                  {"jumping_pair", "pair.continuous_at_cutoff"},
                                                  {"unscaled_pair", "pair.special_bonds"}};
  for (const auto& [plugin, check] : own) {
    const auto res = test::pdyn({"check", plugin, "--plugin-path", kBroken});
    const auto verdicts = pair_verdicts(res.out);
    EXPECT_EQ(verdicts.size(), 6u) << res.out;
    for (const auto& [name, verdict] : verdicts) {
      EXPECT_EQ(verdict, name == check ? "FAIL" : (verdict == "skip" ? "skip" : "pass"))
          << plugin << ": " << name << "\n"
          << res.out;
    }
  }
}

// pair.selecting_loop (issue 42): a central law that branches at the cutoff
// is told the one line that makes the loop select; a hand-written pair
// force that offers no PairLoop is told nothing of its loop.
TEST(Check, SelectingLoopAdvisesACentralLawThatBranches) {
  const auto branches = test::pdyn({"check", "jumping_pair", "--plugin-path", kBroken});
  EXPECT_EQ(pair_verdicts(branches.out).at("pair.selecting_loop"), "skip") << branches.out;
  EXPECT_NE(branches.out.find("static constexpr bool evaluate_beyond_cutoff = true;"),
            std::string::npos)
      << branches.out;
  const auto by_hand = test::pdyn({"check", "stale_pair_list", "--plugin-path", kBroken});
  EXPECT_EQ(pair_verdicts(by_hand.out).at("pair.selecting_loop"), "skip") << by_hand.out;
  EXPECT_NE(by_hand.out.find("does not report its loop"), std::string::npos) << by_hand.out;
}

// Each broken bonded force fails its own bonded.* check and passes the
// others that apply to it.
TEST(Check, EachBrokenBondedForceFailsOnlyItsOwnBondedCheck) {
  const std::map<std::string, std::string> own = {{"bond_one_sided", "bonded.third_law"},
                                                  {"bond_bad_energy", "bonded.gradient"},
                                                  {"bond_bad_hessian", "bonded.jacobian_exact"},
                                                  {"bond_indefinite", "bonded.jacobian_definite"},
                                                  {"bond_drops_term", "bonded.matches_terms"}};
  for (const auto& [plugin, check] : own) {
    const auto res = test::pdyn({"check", plugin, "--plugin-path", kBroken});
    std::map<std::string, std::string> verdicts;
    std::istringstream lines(res.out);
    for (std::string line; std::getline(lines, line);) {
      if (line.rfind("bonded.", 0) != 0) continue;
      std::istringstream row(line);
      std::string name, verdict;
      row >> name >> verdict;
      verdicts[name] = verdict;
    }
    EXPECT_EQ(verdicts.size(), 5u) << res.out;
    for (const auto& [name, verdict] : verdicts) {
      EXPECT_EQ(verdict, name == check ? "FAIL" : "pass") << plugin << ": " << name << "\n"
                                                          << res.out;
    }
  }
}

// A process that already ran threads (a Python session after a run, this
// test program) forks the checks' child: libgomp cannot start a team there,
// and bonded.matches_terms used to hang until its 10 s limit and fail a
// correct plugin. It now compares one thread only and says why.
TEST(Check, ChecksForkedFromAThreadedProcessDoNotHang) {
  // The in-process checks of spring run its 2-thread loop here first.
  const auto* spring = test::shipped_plugins().find(PluginKind::Force, "spring");
  ASSERT_NE(spring, nullptr);
  ASSERT_TRUE(conformance::all_passed(conformance::run_checks(*spring->descriptor, {.seed = 7})));
  const auto res = test::pdyn({"check", "spring"});
  EXPECT_EQ(res.status, 0) << res.out << res.err;
  EXPECT_NE(res.out.find("1 and 2 threads not compared (a child of a threaded process"),
            std::string::npos)
      << res.out;
}

TEST(Check, PairForcesPassThePairChecks) {
  // lennard_jones declares its energy continuous with shift: true (the kit
  // turns its boolean `shift` on); soft_contact declares nothing there.
  const std::map<std::string, std::map<std::string, conformance::Verdict>> expected = {
      {"lennard_jones",
       {{"pair.newton_third_law", conformance::Verdict::Pass},
        {"pair.gradient", conformance::Verdict::Pass},
        {"pair.matches_brute_force", conformance::Verdict::Pass},
        {"pair.special_bonds", conformance::Verdict::Pass},
        {"pair.continuous_at_cutoff", conformance::Verdict::Pass},
        {"pair.selecting_loop", conformance::Verdict::Pass}}},
      {"soft_contact",  // a general law (radii, velocities): it branches
       {{"pair.newton_third_law", conformance::Verdict::Pass},
        {"pair.gradient", conformance::Verdict::Pass},
        {"pair.matches_brute_force", conformance::Verdict::Pass},
        {"pair.special_bonds", conformance::Verdict::Pass},
        {"pair.continuous_at_cutoff", conformance::Verdict::Skip},
        {"pair.selecting_loop", conformance::Verdict::Skip}}},
      {"spring",  // not a pair force
       {{"pair.newton_third_law", conformance::Verdict::Skip},
        {"pair.gradient", conformance::Verdict::Skip},
        {"pair.matches_brute_force", conformance::Verdict::Skip},
        {"pair.special_bonds", conformance::Verdict::Skip},
        {"pair.continuous_at_cutoff", conformance::Verdict::Skip},
        {"pair.selecting_loop", conformance::Verdict::Skip}}}};
  for (const auto& [plugin, verdicts] : expected) {
    const auto* r = test::shipped_plugins().find(PluginKind::Force, plugin);
    ASSERT_NE(r, nullptr) << plugin;
    const auto results = conformance::run_checks(*r->descriptor, {.seed = 3});
    for (const auto& [name, verdict] : verdicts) {
      const auto row = std::find_if(results.begin(), results.end(),
                                    [&](const auto& c) { return c.name == name; });
      ASSERT_NE(row, results.end()) << plugin << ": no " << name;
      EXPECT_EQ(row->verdict, verdict) << plugin << ": " << name << ": " << row->detail << "\n"
                                       << conformance::table(results);
    }
  }
}

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
  EXPECT_EQ(p.reals("ks"), std::vector<double>{1.0});
  EXPECT_FALSE(p.has("rest"));  // optional without default: left out
}

}  // namespace
}  // namespace pdyn
