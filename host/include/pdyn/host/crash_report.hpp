// Naming the plugin that crashed: the fatal-signal handler of `pdyn run`,
// which reads the "current plugin call" record that the kernel keeps around
// every call into a plugin (pdyn/kernel/plugin_call.hpp).
//
// A plugin that dereferences a null pointer kills the process with SIGSEGV;
// no exception is thrown, so the step loop's own fault handling never sees
// it. The record costs a few stores per plugin call (no allocation, no
// lock); the handler, installed only while a run steps, turns the crash
// into one line:
//   pdyn: force 'nbody' (scene.yaml:12:5, library /p/pdyn_force_nbody.so)
//         crashed with SIGSEGV in add_forces at step 12
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "pdyn/host/export.hpp"
#include "pdyn/kernel/plugin_call.hpp"

namespace pdyn {

struct Scene;

namespace crash {

/// "SIGSEGV", "SIGABRT", ... for the usual signals; nullptr for others.
/// Async-signal-safe (returns a string literal).
PDYN_HOST_API const char* signal_name(int sig) noexcept;

/// The step the runner is taking, for the crash message (one store).
PDYN_HOST_API void set_step(std::int64_t step) noexcept;

/// While alive, turns the fatal-signal report on for the runs of this
/// process (run_scene installs a FatalSignalReport while it steps): `pdyn
/// run` does, for its one run; tests, renderers and servers that run scenes
/// in-process keep their own signal handling. Process-wide, as signal
/// dispositions are.
class PDYN_HOST_API ReportCrashes {
 public:
  ReportCrashes() noexcept;
  ~ReportCrashes();
  ReportCrashes(const ReportCrashes&) = delete;
  ReportCrashes& operator=(const ReportCrashes&) = delete;
};
PDYN_HOST_API bool reporting_enabled() noexcept;

/// While alive, SIGSEGV, SIGBUS, SIGFPE, SIGILL and SIGABRT make the
/// process print one line on stderr naming the plugin call in progress (its
/// kind, name, scene location, library, hook and the step), remove the
/// run's temporary output files, and die of the same signal (exit status
/// 128 + signal). Everything the handler prints is formatted here, before
/// the run; the handler itself only copies bytes, calls write(2) and
/// unlink(2). One at a time per process.
class PDYN_HOST_API FatalSignalReport {
 public:
  FatalSignalReport(const Scene& scene, const std::vector<std::filesystem::path>& temp_files);
  ~FatalSignalReport();
  FatalSignalReport(const FatalSignalReport&) = delete;
  FatalSignalReport& operator=(const FatalSignalReport&) = delete;

  /// A checkpoint has been written: from now on the temporary output files
  /// are what `pdyn run --resume CHECKPOINT` continues, so a crash keeps
  /// them and names them instead of removing them.
  void keep_temp_files(const std::filesystem::path& checkpoint);

 private:
  bool installed_ = false;
};

}  // namespace crash
}  // namespace pdyn
