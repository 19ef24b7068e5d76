// `pdyn convert IN [-o SCENE.yaml]`: a LAMMPS input script as a scene
// (issue 44 item 6; the converter is the host's, pdyn/host/convert.hpp).
// The scene goes to standard output, or to SCENE.yaml through
// write_text_output: never a half-written scene.
#include "pdyn/host/convert.hpp"

#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <utility>
#include <vector>

#include "commands.hpp"
#include "sdk_commands.hpp"

namespace pdyn::cli {

namespace {

namespace fs = std::filesystem;

struct ConvertArgs {
  std::string input, output;
  std::vector<std::pair<std::string, std::string>> variables;  // --var NAME VALUE
};

int cmd_convert(const ConvertArgs& a, std::ostream& out, std::ostream& err) {
  std::ifstream in(a.input, std::ios::binary);
  if (!in) {
    err << fmt::format("pdyn: cannot read {} (expected a LAMMPS input script)\n", a.input);
    return kBadInput;
  }
  std::stringstream text;
  text << in.rdbuf();
  // The files the scene reads are written before it, beside it: a scene
  // that exists finds them.
  const fs::path scene(a.output);
  ConvertOptions options;
  for (const auto& [name, value] : a.variables) options.variables[name] = value;
  // read_data's names are relative to this directory, as lmp's; the scene
  // names them from its own folder.
  if (!a.output.empty()) {
    std::error_code ec;
    const fs::path from = fs::relative(fs::current_path(), fs::absolute(scene).parent_path(), ec);
    if (!ec && from != ".") options.data_folder = from.generic_string();
  }
  const ConvertedScene converted = convert_lammps_script(
      text.str(), a.input, a.output.empty() ? std::string() : scene.stem().string(), options);
  if (!converted.files.empty() && a.output.empty()) {
    err << fmt::format(
        "pdyn: {} makes its own atoms, which go to a data file beside the scene (expected pdyn "
        "convert {} -o SCENE.yaml)\n",
        a.input, a.input);
    return kBadInput;
  }
  for (const auto& [name, contents] : converted.files) {
    const int status = write_text_output(contents, (scene.parent_path() / name).string(), out, err);
    if (status != kOk) return status;
  }
  return write_text_output(converted.scene, a.output, out, err);
}

}  // namespace

SdkCommand add_convert_command(CLI::App& app) {
  auto a = std::make_shared<ConvertArgs>();
  CLI::App* sub =
      app.add_subcommand("convert", "convert a LAMMPS input script to a scene (docs/lammps.md)");
  sub->add_option("input", a->input, "the LAMMPS input script (in.*)")->required();
  sub->add_option("--output,-o", a->output,
                  "write the scene to this file instead of standard output");
  sub->add_option("--var", a->variables,
                  "NAME VALUE: define the script's variable NAME, as lmp -var NAME VALUE "
                  "(repeatable)")
      ->type_size(2)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  return {sub, [a](std::ostream& out, std::ostream& err) { return cmd_convert(*a, out, err); }};
}

}  // namespace pdyn::cli
