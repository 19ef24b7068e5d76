// The `pdyn` command line: run, validate, plugins.
#pragma once

#include <iosfwd>
#include <string>
#include <vector>

namespace pdyn::cli {

/// Exit statuses shared by every command.
enum Exit : int {
  kOk = 0,
  kFailure = 1,        ///< an output file could not be written, or an internal error
  kBadInput = 2,       ///< bad scene or command line
  kPluginFault = 3,    ///< a plugin the scene needs cannot be used
  kNonFinite = 4,      ///< the simulation blew up (NaN or infinity)
  kInterrupted = 130,  ///< SIGINT or SIGTERM: stopped cleanly after a step, checkpoint written
};

/// Runs `pdyn ARGS...` (without the program name), writing to `out` and
/// `err`; returns the exit status. `terminal` says whether `err` is a
/// terminal, which enables the progress bar.
int run_command(const std::vector<std::string>& args, std::ostream& out, std::ostream& err,
                bool terminal = false);

}  // namespace pdyn::cli
