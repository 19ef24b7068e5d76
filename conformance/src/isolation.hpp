// Crash isolation for the conformance kit: the checks run in a child
// process, so that a plugin that crashes, aborts or hangs fails the check it
// was in instead of taking the kit (and `pdyn check`) down with it.
//
// The checks of one kind share state: the plugin object construct.defaults
// built, the seeded generator that each check draws its configurations
// from, the obstacle and drops the collider checks find. So they do not run
// each in a fresh process; one child runs the whole sequence, as the kit
// does in-process, and streams each result to the parent through a pipe
// as soon as it is known, announcing each check before it starts. When the
// child dies (a fatal signal, or exit) or a check outlives the time limit
// (the parent kills the child), the parent records the check in progress as
// failed ("crashed with SIGSEGV", "timed out after 10 s") and starts a new
// child that runs the sequence again from the start, taking the recorded
// result for that check instead of running it. A healthy plugin's report is
// the same, bit for bit, as in-process.
#pragma once

#include <functional>
#include <map>
#include <string>
#include <vector>

#include "pdyn/conformance.hpp"

namespace pdyn::conformance::detail {

/// The child's end of the pipe: what the check sequence reports through
/// while it runs isolated.
class Worker {
 public:
  Worker(int fd, const std::map<std::size_t, CheckResult>& replaced)
      : fd_(fd), replaced_(replaced) {}
  /// Before the check `name`, the next entry of `out`: sends what `out` got
  /// since the last call and announces the check. Returns the result to
  /// push instead of running the check (it crashed an earlier child), or null.
  const CheckResult* begin(const std::vector<CheckResult>& out, const std::string& name);
  /// Sends what `out` got since the last call.
  void flush(const std::vector<CheckResult>& out);
  /// Sends the rest of `out` and the end mark.
  void finish(const std::vector<CheckResult>& out);

 private:
  int fd_;
  const std::map<std::size_t, CheckResult>& replaced_;
  std::size_t sent_ = 0;
};

/// The Worker of the check sequence running on this thread, or null when
/// the checks run in-process.
Worker* current_worker() noexcept;

/// False in a child forked from a process that already ran threads (a
/// Python session that stepped a simulation, a test program): GNU libgomp
/// cannot start a team there (the child hangs), so a check that compares
/// thread counts compares one only and says so. True otherwise.
bool threads_usable() noexcept;

/// Runs `sequence` in child processes as described above, each check with
/// `timeout` seconds, and returns the report it filled.
std::vector<CheckResult> run_isolated(
    const std::function<void(std::vector<CheckResult>&)>& sequence, double timeout);

}  // namespace pdyn::conformance::detail
