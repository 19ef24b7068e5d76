// The `pdyn` command line: run, validate, plugins.
#pragma once

#include <exception>
#include <iosfwd>
#include <string>
#include <vector>

namespace CLI {
class App;
}

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
/// Reports an exception from loading or running a scene on `err` and returns
/// the exit status for it: a SceneError's diagnostics (2), a PluginError (3),
/// a CheckpointError (2), anything else (1).
int report_error(const std::exception_ptr& error, std::ostream& err);

/// Writes `text` to `output` (beside it under a temporary name, then
/// renamed: never a half-written file), or to `out` when `output` is empty.
/// Returns kOk, or kFailure after saying on `err` that it cannot write.
int write_text_output(const std::string& text, const std::string& output, std::ostream& out,
                      std::ostream& err);

/// Adds `--plugin-path DIR` to `sub`: repeatable, one folder per occurrence
/// (so that `--plugin-path DIR scene.yaml` leaves the scene to the positional
/// argument), and refused unless DIR is an existing folder, since a
/// misspelled one would otherwise only show up later as an unknown plugin.
void add_plugin_path_option(CLI::App* sub, std::vector<std::string>& plugin_path,
                            const char* help = nullptr);

/// Adds `--set KEY.PATH=VALUE` and `--plugin-path DIR` (both repeatable) to
/// a command that loads a scene.
void add_scene_options(CLI::App* sub, std::vector<std::string>& sets,
                       std::vector<std::string>& plugin_path);

int run_command(const std::vector<std::string>& args, std::ostream& out, std::ostream& err,
                bool terminal = false);

}  // namespace pdyn::cli
