// pdyn/conformance.hpp — the plugin conformance kit: checks that a plugin
// behaves as its descriptor claims (the physics, not only the interface).
//
// `pdyn check NAME` runs these checks and prints their table; a plugin
// author's own tests can call them directly:
//
//   #include <pdyn/conformance.hpp>
//   TEST(Vortex, Conforms) {
//     const auto report = pdyn::conformance::run_checks(*my_descriptor(), {});
//     EXPECT_TRUE(pdyn::conformance::all_passed(report)) << pdyn::conformance::table(report);
//   }
//
// Each check states its bound; docs/plugins.md lists them all.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "pdyn/plugin.hpp"

namespace pdyn::conformance {

enum class Verdict { Pass, Fail, Skip };

/// "pass", "FAIL" or "skip".
const char* verdict_name(Verdict v);

/// The outcome of one check: `measured` is compared with `bound` (both in
/// the units `what` names); `detail` says what was measured, or why it failed.
struct CheckResult {
  std::string name;  ///< e.g. "force.net_force_zero"
  Verdict verdict = Verdict::Pass;
  double measured = 0.0;
  double bound = 0.0;
  std::string detail;
};

/// Seconds a check may run, isolated, before it fails as hung: 100 times
/// what the whole kit takes for the slowest shipped plugin (0.1 s).
inline constexpr double kDefaultTimeout = 10.0;

struct Options {
  std::uint64_t seed = 1;  ///< seeds the random particle configurations
  /// Run the checks in a child process (fork), so that a plugin that
  /// crashes (any fatal signal), aborts, exits or hangs fails the check it
  /// was in ("crashed with SIGSEGV", "timed out after 10 s") and the other
  /// checks still run. The report is the same as in-process otherwise.
  /// `pdyn check` does this. The child runs OpenMP with one thread (GNU
  /// libgomp cannot start a team in a child forked from a process that had
  /// one; results do not depend on the thread count).
  bool isolate = false;
  /// With `isolate`: seconds a check may run without finishing (> 0).
  double timeout = kDefaultTimeout;
};

/// Runs every check for the descriptor's kind. Never throws: a plugin that
/// throws fails the check that was running, naming the exception. Besides
/// calling the plugin directly, it loads small scenes holding it through the
/// kernel's scene loader (params.bad_rejected) and runs it in two threads at
/// once (threads.two_systems). Takes well under a second for the shipped plugins.
std::vector<CheckResult> run_checks(const PluginDescriptor& descriptor, const Options& options);

/// Parameters to construct the plugin with, for a system of `n` (>= 4)
/// particles: a parameter's declared sample (ParamSpec::sample) if it has
/// one, else its default, else for a required parameter a typical value of
/// its type: a number 1 (or inside the declared range), a vector
/// [0.3, -0.2, 0.9], an IndexList [0, 1, n - 1], IndexPairs [[0, 1], [1, 2],
/// [2, 3], [0, n - 1]], IndexTriples [[0, 1, 2], [1, 2, 3]], IndexQuads
/// [[0, 1, 2, 3], [1, 2, 3, 4]]. Optional parameters without either are
/// left out. Every check builds the plugin with these, but one:
Params sample_params(const PluginDescriptor& descriptor, Index n);

/// What a scene that gives only the required keys gets, for `n` particles:
/// each required parameter at its sample (else the typical value above),
/// every other at its default, an optional one without a default left out
/// (its sample unused). `constraint.satisfied_at_creation` builds the
/// constraint with these: a geometry the scene leaves out (a rod's length, a
/// radius) must come from the initial positions, whatever sample a check
/// exercises it with.
Params default_params(const PluginDescriptor& descriptor, Index n);

/// True when no check failed (skipped checks do not count).
bool all_passed(const std::vector<CheckResult>& results);

/// The report as an aligned text table: check, verdict, measured, bound, detail.
std::string table(const std::vector<CheckResult>& results);

/// The report as JUnit XML (one testsuite named after the plugin).
std::string junit_xml(const PluginDescriptor& descriptor, const std::vector<CheckResult>& results);

}  // namespace pdyn::conformance
