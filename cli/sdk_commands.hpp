// The plugin-author commands: `pdyn check` (conformance kit, check.cpp),
// `pdyn new` (project templates, new.cpp) and `pdyn schema` (schema.cpp).
// Each lives in its own file; commands.cpp only registers them.
#pragma once

#include <functional>
#include <iosfwd>
#include <vector>

namespace CLI {
class App;
}

namespace pdyn::cli {

/// A subcommand added to the app: run() executes it once the command line
/// has been parsed and `sub` was chosen; it returns the exit status.
struct SdkCommand {
  CLI::App* sub = nullptr;
  std::function<int(std::ostream& out, std::ostream& err)> run;
};

/// `pdyn check NAME [--plugin-path DIR] [--junit FILE] [--seed N]`.
SdkCommand add_check_command(CLI::App& app);

/// `pdyn new force|solver|collider NAME [DIR]`.
SdkCommand add_new_command(CLI::App& app);

/// `pdyn schema [--plugin-path DIR] [--output FILE]`.
SdkCommand add_schema_command(CLI::App& app);

/// `pdyn convert IN [--output SCENE.yaml]` (convert.cpp).
SdkCommand add_convert_command(CLI::App& app);

/// `pdyn serve SCENE [--port N] [--host ADDR] [--viewer DIR]` (serve.cpp).
SdkCommand add_serve_command(CLI::App& app);

/// Every SDK command, in the order of `pdyn --help`.
std::vector<SdkCommand> add_sdk_commands(CLI::App& app);

}  // namespace pdyn::cli
