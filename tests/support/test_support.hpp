// Helpers shared by pdyn's tests.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "pdyn/host/registry.hpp"
#include "pdyn/host/runner.hpp"
#include "pdyn/host/scene.hpp"

namespace pdyn::test {

/// The registry of the shipped plugins in the build tree (discovered once).
const PluginRegistry& shipped_plugins();

/// Loads a scene from YAML text (named "test.yaml" in messages).
Scene load_text(const std::string& yaml, const std::vector<Override>& overrides = {});

/// The located problems load_text reports for `yaml` (SceneError's text),
/// or "(loaded without error)".
std::string load_problems(const std::string& yaml);

/// Result of running the `pdyn` command in-process.
struct CommandResult {
  int status = -1;
  std::string out, err;
};
/// Runs `pdyn ARGS...` in-process.
CommandResult pdyn(const std::vector<std::string>& args);

/// A fresh empty directory under the system temp folder, removed at exit.
std::filesystem::path temp_dir(const std::string& name);

/// Writes `text` to `path` (creating folders) and returns the path.
std::filesystem::path write_file(const std::filesystem::path& path, const std::string& text);

/// Path of a file in the source tree, e.g. source_path("configs/demo.yaml").
std::filesystem::path source_path(const std::string& relative);

/// Path of a shared test scene, tests/scenes/shared/NAME (e.g. "cloth.yaml"):
/// the one definition of a set-up that several tests (and the benchmarks)
/// vary with overrides instead of copying it.
std::filesystem::path shared_scene(const std::string& name);

/// Loads shared_scene(NAME) with the shipped plugins and `overrides`.
Scene load_shared(const std::string& name, const std::vector<Override>& overrides = {});

/// The bytes of a file ("" if it cannot be read).
std::string read_bytes(const std::filesystem::path& path);

/// Every regular file under `dir`, by its path relative to `dir`, with its
/// bytes: compared before and after a run to show what it changed.
std::map<std::string, std::string> snapshot(const std::filesystem::path& dir);

/// `text` split at newlines (without them).
std::vector<std::string> split_lines(const std::string& text);

/// A CSV file of numbers with a header row (an energy file, a LAMMPS
/// reference.thermo), as column name -> values.
std::map<std::string, std::vector<double>> csv_columns(const std::filesystem::path& file);

}  // namespace pdyn::test
