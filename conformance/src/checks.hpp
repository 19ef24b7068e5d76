// The conformance kit's internal interface: the checks of each plugin kind,
// each module in a file of its own, and the result helpers they all share.
// report.cpp runs them in sequence for a descriptor's kind (run_checks).
#pragma once

#include <functional>
#include <random>
#include <string>
#include <vector>

#include "pdyn/conformance.hpp"

namespace pdyn::conformance::detail {

// ---- results (report.cpp) ----

CheckResult result(std::string name, bool pass, double measured, double bound, std::string detail);

CheckResult skip(std::string name, std::string why);

/// Runs `check`, turning an exception from the plugin into a failed check.
/// Isolated (Options::isolate), it tells the parent process which check runs,
/// and skips a check that crashed an earlier child, taking its result.
void guarded(std::vector<CheckResult>& out, const std::string& name,
             const std::function<CheckResult()>& check);

// ---- the checks of each kind ----

/// forces.cpp: construct.defaults, deterministic, read_only_state,
/// adds_only, finite_on_degenerate, the force.* checks, then pair_checks.
void force_checks(const PluginDescriptor& d, const Options& o, std::vector<CheckResult>& out);

/// pairs.cpp: the pair.* checks of a force that offers pdyn::PairReference
/// (pdyn/pair.hpp; every PairForce does), or their skips. `params`: what
/// the other checks built the force with; `force`: that object.
void pair_checks(const PluginDescriptor& d, const Params& params, const Force& force,
                 std::mt19937_64& rng, std::vector<CheckResult>& out);

/// bonded.cpp: the bonded.* checks of a force that offers
/// pdyn::BondedReference (pdyn/bonded_reference.hpp; every BondedForce does), or their
/// skips, on random states away from rest.
void bonded_checks(const PluginDescriptor& d, const Params& params, const Force& force,
                   std::mt19937_64& rng, std::vector<CheckResult>& out);

/// solvers.cpp: construct.defaults, deterministic, finite_on_degenerate and
/// the solver.* checks.
void solver_checks(const PluginDescriptor& d, const Options& o, std::vector<CheckResult>& out);

/// colliders.cpp: construct.defaults, deterministic, read_only_state,
/// finite_on_degenerate and the collider.* checks.
void collider_checks(const PluginDescriptor& d, const Options& o, std::vector<CheckResult>& out);

/// writers.cpp: construct.defaults and the writer.* checks: frames written
/// in a scratch folder, complete only after commit, read back, resumed.
void writer_checks(const PluginDescriptor& d, const Options& o, std::vector<CheckResult>& out);

/// constraints.cpp: construct.defaults and the constraint.* checks: a
/// well-formed pattern, deterministic, read-only, finite when particles
/// coincide and near singular spots (the origin, axes, the parameters'
/// points and directions), satisfied where made with the default
/// parameters, and J, c_t and b against finite differences of C.
void constraint_checks(const PluginDescriptor& d, const Options& o, std::vector<CheckResult>& out);

// ---- checks of every kind ----

/// threads.cpp: "threads.two_systems": two systems, each with its own plugin
/// object, stepped in two threads at once must end bit-identical to the same
/// runs in one thread.
CheckResult check_threads(const PluginDescriptor& d, const Options& o);

/// bad_params.cpp: "params.bad_rejected": bad values generated from the
/// descriptor, each in a small scene of the particles `x` given to the real
/// scene loader, must be refused with a message naming the key; the sample
/// values must be accepted.
CheckResult check_bad_params(const PluginDescriptor& d, const Params& sample, const Matrix3X& x);

}  // namespace pdyn::conformance::detail
