// `pdyn check`: runs the conformance kit on one plugin and prints its table.
//   exit 0: every check passed; 1: a check failed (a check that crashed or
//   hung included: the checks run in a child process); 2: no such plugin
//   (or a bad command line); 3: the plugin's library cannot be used.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <fstream>
#include <memory>
#include <ostream>

#include "commands.hpp"
#include "pdyn/conformance.hpp"
#include "pdyn/host/registry.hpp"
#include "pdyn/text.hpp"
#include "sdk_commands.hpp"

namespace pdyn::cli {

namespace fs = std::filesystem;

namespace {

struct CheckArgs {
  std::string name;  // a plugin name, or the path of a plugin library
  std::vector<std::string> plugin_path;
  std::string junit;
  std::uint64_t seed = 1;
  double timeout = conformance::kDefaultTimeout;
  bool in_process = false;
};

int cmd_check(const CheckArgs& a, std::ostream& out, std::ostream& err) {
  PluginRegistry registry;
  const PluginRecord* record = nullptr;
  if (a.name.find('/') != std::string::npos || fs::path(a.name).extension() == ".so") {
    // A library file: load just that one.
    if (!registry.load_library(a.name)) {
      const auto& f = registry.faults().back();
      err << fmt::format("pdyn: {}: plugin '{}': {}\n", f.library.string(), f.plugin, f.message);
      return kPluginFault;
    }
    record = &registry.plugins().back();
  } else {
    registry.discover(PluginRegistry::search_path(
        std::vector<fs::path>(a.plugin_path.begin(), a.plugin_path.end()),
        DefaultFolders::LibraryAndProgram));
    try {
      registry.require_healthy(a.name);
    } catch (const PluginError& e) {
      err << e.what() << "\n";
      return kPluginFault;
    }
    record = registry.find_any(a.name);
    if (!record) {
      std::vector<std::string> all;
      for (const auto& p : registry.plugins()) all.push_back(p.descriptor->name);
      const std::string guess = closest_match(a.name, all);
      err << fmt::format("pdyn: no plugin named '{}' ({}expected one of: {})\n", a.name,
                         guess.empty() ? "" : fmt::format("did you mean '{}'? ", guess), join(all));
      return kBadInput;
    }
  }
  const PluginDescriptor& d = *record->descriptor;
  // Isolated: a crash or a hang fails its check instead of ending pdyn.
  // The `pdyn` process has run no plugin code and no OpenMP team before
  // this point, which makes it a safe place to fork from.
  const auto results =
      conformance::run_checks(d, {.seed = a.seed, .isolate = !a.in_process, .timeout = a.timeout});
  out << fmt::format("pdyn check: {} {} {} ({}), seed {}\n\n", kind_name(d.kind), d.name, d.version,
                     record->library.string(), a.seed);
  if (record->optimised == false) {
    out << fmt::format(
        "warning: {} was compiled without optimisation: its code may run 10 to 100 "
        "times slower (expected a build with CMAKE_BUILD_TYPE=Release or "
        "RelWithDebInfo; pdyn_add_plugin optimises when no build type is set)\n\n",
        record->library.string());
  }
  out << conformance::table(results);
  std::size_t failed = 0;
  std::vector<std::string> failed_names;
  for (const auto& r : results) {
    if (r.verdict == conformance::Verdict::Fail) failed_names.push_back(r.name);
  }
  failed = failed_names.size();
  if (!a.junit.empty()) {
    std::ofstream file(a.junit);
    file << conformance::junit_xml(d, results);
    if (!file) {
      err << fmt::format("pdyn: cannot write {}\n", a.junit);
      return kFailure;
    }
  }
  if (failed > 0) {
    out << fmt::format("\n{}: {} check(s) failed: {}\n", d.name, failed, join(failed_names));
    return kFailure;
  }
  out << fmt::format("\n{}: all checks passed\n", d.name);
  return kOk;
}

}  // namespace

SdkCommand add_check_command(CLI::App& app) {
  auto a = std::make_shared<CheckArgs>();
  CLI::App* sub =
      app.add_subcommand("check", "run the conformance kit on a plugin (by name or library path)");
  sub->add_option("name", a->name, "plugin name, or path of a plugin library")->required();
  add_plugin_path_option(sub, a->plugin_path);
  sub->add_option("--junit", a->junit, "also write the report as JUnit XML to this file");
  sub->add_option("--seed", a->seed, "seed of the generated particle configurations");
  sub->add_option("--timeout", a->timeout,
                  fmt::format("seconds a check may run before it fails as hung (default {:g})",
                              conformance::kDefaultTimeout))
      ->check(CLI::PositiveNumber);
  sub->add_flag("--in-process", a->in_process,
                "run the checks in this process rather than in a child process (for a "
                "debugger): a plugin that crashes or hangs then takes pdyn check with it");
  return {sub, [a](std::ostream& out, std::ostream& err) { return cmd_check(*a, out, err); }};
}

std::vector<SdkCommand> add_sdk_commands(CLI::App& app) {
  return {add_check_command(app), add_new_command(app), add_schema_command(app)};
}

}  // namespace pdyn::cli
