// `pdyn convert IN [-o SCENE.yaml]`: a LAMMPS input script as a scene
// (issue 44 item 6; the converter is the host's, pdyn/host/convert.hpp).
// The scene goes to standard output, or is written beside SCENE.yaml under
// a temporary name and renamed: never a half-written scene.
#include "pdyn/host/convert.hpp"

#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "commands.hpp"
#include "sdk_commands.hpp"

namespace pdyn::cli {

namespace {

namespace fs = std::filesystem;

struct ConvertArgs {
  std::string input, output;
};

int cmd_convert(const ConvertArgs& a, std::ostream& out, std::ostream& err) {
  std::ifstream in(a.input, std::ios::binary);
  if (!in) {
    err << fmt::format("pdyn: cannot read {} (expected a LAMMPS input script)\n", a.input);
    return kBadInput;
  }
  std::stringstream text;
  text << in.rdbuf();
  const std::string scene = convert_lammps_input(text.str(), a.input);
  if (a.output.empty()) {
    out << scene;
    return kOk;
  }
  const fs::path target(a.output), tmp = fs::path(a.output + ".tmp");
  std::ofstream file(tmp, std::ios::binary);
  file << scene;
  file.close();
  std::error_code ec;
  if (!file || (fs::rename(tmp, target, ec), ec)) {
    fs::remove(tmp, ec);
    err << fmt::format("pdyn: cannot write {}\n", a.output);
    return kFailure;
  }
  return kOk;
}

}  // namespace

SdkCommand add_convert_command(CLI::App& app) {
  auto a = std::make_shared<ConvertArgs>();
  CLI::App* sub =
      app.add_subcommand("convert", "convert a LAMMPS input script to a scene (docs/lammps.md)");
  sub->add_option("input", a->input, "the LAMMPS input script (in.*)")->required();
  sub->add_option("--output,-o", a->output,
                  "write the scene to this file instead of standard output");
  return {sub, [a](std::ostream& out, std::ostream& err) { return cmd_convert(*a, out, err); }};
}

}  // namespace pdyn::cli
