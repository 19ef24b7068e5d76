#include "support/test_support.hpp"

#include <unistd.h>

#include <fstream>
#include <sstream>

#include "commands.hpp"

namespace pdyn::test {

namespace fs = std::filesystem;

const PluginRegistry& shipped_plugins() {
  static const PluginRegistry registry = [] {
    PluginRegistry r;
    r.discover({PDYN_PLUGIN_DIR});
    return r;
  }();
  return registry;
}

Scene load_text(const std::string& yaml, const std::vector<Override>& overrides) {
  return load_scene_text(yaml, "test.yaml", shipped_plugins(), overrides);
}

std::string load_problems(const std::string& yaml) {
  try {
    load_text(yaml);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "(loaded without error)";
}

CommandResult pdyn(const std::vector<std::string>& args) {
  std::ostringstream out, err;
  CommandResult r;
  r.status = cli::run_command(args, out, err, false);
  r.out = out.str();
  r.err = err.str();
  return r;
}

fs::path temp_dir(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("pdyn-test-" + std::to_string(::getpid())) / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  static const struct Cleanup {
    fs::path root = fs::temp_directory_path() / ("pdyn-test-" + std::to_string(::getpid()));
    ~Cleanup() {
      std::error_code ec;
      fs::remove_all(root, ec);
    }
  } cleanup;
  return dir;
}

fs::path write_file(const fs::path& path, const std::string& text) {
  if (path.has_parent_path()) fs::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

fs::path source_path(const std::string& relative) { return fs::path(PDYN_SOURCE_DIR) / relative; }

fs::path shared_scene(const std::string& name) {
  return source_path("tests/scenes/shared/" + name);
}

Scene load_shared(const std::string& name, const std::vector<Override>& overrides) {
  return load_scene(shared_scene(name), shipped_plugins(), overrides);
}

std::string read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::map<std::string, std::string> snapshot(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (e.is_regular_file()) files[fs::relative(e.path(), dir).string()] = read_bytes(e.path());
  }
  return files;
}

std::vector<std::string> split_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  return lines;
}

std::map<std::string, std::vector<double>> csv_columns(const std::filesystem::path& file) {
  std::map<std::string, std::vector<double>> out;
  const auto lines = split_lines(read_bytes(file));
  std::vector<std::string> names;
  for (std::size_t k = 0; k < lines.size(); ++k) {
    if (lines[k].empty()) continue;
    std::stringstream row(lines[k]);
    std::string cell;
    for (std::size_t c = 0; std::getline(row, cell, ','); ++c) {
      if (k == 0) {
        names.push_back(cell);
      } else {
        out[names.at(c)].push_back(std::stod(cell));
      }
    }
  }
  return out;
}

}  // namespace pdyn::test
