// `pdyn new force|solver|collider|pair|bonded|writer|constraint NAME [DIR]`: writes a ready
// out-of-tree plugin project (CMakeLists.txt, NAME.cpp, test_NAME.cpp, README.md, scene.yaml)
// that builds against the installed SDK and passes `pdyn check` as generated.
//   exit 0: written; 2: bad name, kind or folder; 1: a file could not be written.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <memory>
#include <ostream>
#include <random>
#include <system_error>

#include "commands.hpp"
#include "pdyn/host/registry.hpp"
#include "sdk_commands.hpp"
#include "templates.hpp"

namespace pdyn::cli {

namespace fs = std::filesystem;

namespace {

struct NewArgs {
  std::string kind;
  std::string name;
  std::string dir;
  std::vector<std::string> plugin_path;
};

std::string replace_all(std::string s, std::string_view from, std::string_view to) {
  for (std::size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size())) {
    s.replace(at, from.size(), to);
  }
  return s;
}

// CMake reserves these target names; pdyn_add_plugin(NAME ...) would fail.
bool reserved_by_cmake(const std::string& name) {
  static const std::array<std::string_view, 9> reserved = {
      "all",        "clean",         "help",
      "install",    "test",          "package",
      "edit_cache", "rebuild_cache", "list_install_components"};
  return std::find(reserved.begin(), reserved.end(), name) != reserved.end();
}

// A sibling of `target` that does not exist yet: the project is written
// there, then renamed into place, so that a failure leaves nothing behind.
fs::path temporary_sibling(const fs::path& target) {
  std::random_device rd;
  for (int attempt = 0; attempt < 100; ++attempt) {
    fs::path p = target;
    p += fmt::format(".pdyn-new-{:08x}", rd());
    std::error_code ec;
    if (!fs::exists(p, ec)) return p;
  }
  throw Error(fmt::format("cannot find a free temporary name beside {}", target.string()));
}

void write_file(const fs::path& file, std::string_view text) {
  std::ofstream out(file, std::ios::binary);
  out.write(text.data(), static_cast<std::streamsize>(text.size()));
  out.close();
  if (!out) throw Error(fmt::format("cannot write {}", file.string()));
}

// The name: valid, not a CMake target, not a plugin already found. Prints
// why not and returns false.
bool name_is_free(const NewArgs& a, std::ostream& err) {
  if (!is_valid_plugin_name(a.name)) {
    err << fmt::format(
        "pdyn: '{}' is not a valid plugin name (expected [a-z0-9_]+, e.g. "
        "my_{})\n",
        a.name, a.kind);
    return false;
  }
  if (reserved_by_cmake(a.name)) {
    err << fmt::format(
        "pdyn: '{}' is a target name that CMake reserves (expected another name, "
        "e.g. my_{})\n",
        a.name, a.name);
    return false;
  }
  // A second plugin of that name would be refused as a duplicate wherever
  // both are on the search path, so refuse the name now.
  PluginRegistry registry;
  registry.discover(
      PluginRegistry::search_path(std::vector<fs::path>(a.plugin_path.begin(), a.plugin_path.end()),
                                  DefaultFolders::LibraryAndProgram));
  if (const PluginRecord* r = registry.find_any(a.name)) {
    err << fmt::format("pdyn: a plugin named '{}' already exists ({}) (expected a new name)\n",
                       a.name, r->library.string());
    return false;
  }

  return true;
}

// The folder: new, or an empty one. Prints why not and returns false.
bool folder_is_free(const fs::path& target, std::ostream& err) {
  std::error_code ec;
  const auto status = fs::symlink_status(target, ec);
  const bool exists = fs::exists(status);
  if (exists && !fs::is_directory(status)) {
    err << fmt::format("pdyn: {} exists and is not a folder (expected a new or empty folder)\n",
                       target.string());
    return false;
  }
  if (exists && !fs::is_empty(target, ec)) {
    err << fmt::format("pdyn: {} exists and is not empty (expected a new or empty folder)\n",
                       target.string());
    return false;
  }

  return true;
}

// The project's files for `kind`: (path relative to the project, template).
// A kind's own file replaces the common one of the same path (a constraint's
// test_NAME.cpp adds a physics test to the conformance run every kind has).
std::vector<std::pair<std::string, std::string_view>> project_files(const NewArgs& a) {
  std::vector<std::pair<std::string, std::string_view>> files;  // (relative path, template)
  for (const auto& t : template_files()) {
    const auto slash = t.path.find('/');
    const std::string_view group = t.path.substr(0, slash);
    if (group != "common" && group != a.kind) continue;
    std::string path = replace_all(std::string(t.path.substr(slash + 1)), "@NAME@", a.name);
    const auto same =
        std::find_if(files.begin(), files.end(), [&](const auto& f) { return f.first == path; });
    if (same == files.end()) {
      files.emplace_back(std::move(path), t.text);
    } else if (group != "common") {
      same->second = t.text;
    }
  }
  return files;
}

// Where the plugin author's guide is: installed beside this program
// (PREFIX/bin/pdyn -> PREFIX/share/doc/pdyn), else in the sources. A pair
// force's author reads pairs.md (the law, PairForce), a bonded force's
// bonded.md (BondedForce, Harmonic), a constraint's constraints.md (C, J,
// c_t and the bias b), the others plugins.md.
std::string guide_for(const std::string& kind) {
  std::error_code ec;
  const std::string page = kind == "pair"         ? "pairs.md"
                           : kind == "bonded"     ? "bonded.md"
                           : kind == "constraint" ? "constraints.md"
                                                  : "plugins.md";
  std::string guide = "docs/" + page + " in the pdyn sources";
  {
    const fs::path program = fs::read_symlink("/proc/self/exe", ec);
    const fs::path installed = program.parent_path() / PDYN_BIN_TO_DOCS / page;
    if (!ec && fs::is_regular_file(installed, ec)) guide = installed.lexically_normal().string();
  }
  return guide;
}

// Writes the project into a temporary sibling of `target`, then renames it
// into place: a failure leaves nothing behind.
void write_project(const NewArgs& a, const fs::path& target,
                   const std::vector<std::pair<std::string, std::string_view>>& files,
                   const std::string& guide) {
  const fs::path absolute = fs::absolute(target).lexically_normal();
  fs::path parent =
      absolute.has_filename() ? absolute.parent_path() : absolute.parent_path().parent_path();
  const fs::path final_path =
      parent / (absolute.has_filename() ? absolute.filename() : absolute.parent_path().filename());
  fs::create_directories(parent);
  const fs::path staging = temporary_sibling(final_path);
  fs::create_directory(staging);
  try {
    for (const auto& [path, text] : files) {
      const fs::path file = staging / path;
      fs::create_directories(file.parent_path());
      // Pair and bonded forces are force plugins (pdyn_add_plugin(... KIND force)).
      const std::string plugin_kind = a.kind == "pair" || a.kind == "bonded" ? "force" : a.kind;
      write_file(file, replace_all(replace_all(replace_all(std::string(text), "@NAME@", a.name),
                                               "@KIND@", plugin_kind),
                                   "@DOCS@", guide));
    }
    // rename(2) replaces an empty folder, so an empty target is fine too.
    fs::rename(staging, final_path);
  } catch (...) {
    std::error_code ec;
    fs::remove_all(staging, ec);
    throw;
  }
}

// What the "next:" line naming the project's test file says to do with it.
// A constraint's test holds for any geometry but for its last test, the
// bowl's exact orbit, which the author replaces with their own.
std::string test_advice(const std::string& kind) {
  if (kind == "constraint") {
    return "your tests; keep the first three (any geometry), replace the bowl's orbit test "
           "with your geometry's exact case (its TODO says what to assert)";
  }
  return "your tests; add your physics (exact solutions, conservation laws) beside the "
         "conformance kit's";
}

int cmd_new(const NewArgs& a, std::ostream& out, std::ostream& err) {
  if (!name_is_free(a, err)) return kBadInput;
  const fs::path target = a.dir.empty() ? fs::path(a.name) : fs::path(a.dir);
  if (!folder_is_free(target, err)) return kBadInput;
  const auto files = project_files(a);
  try {
    write_project(a, target, files, guide_for(a.kind));
  } catch (const std::exception& e) {
    err << fmt::format("pdyn: cannot create {}: {}\n", target.string(), e.what());
    return kFailure;
  }
  out << fmt::format("pdyn: wrote a {} plugin project '{}' in {}:\n", a.kind, a.name,
                     target.string());
  for (const auto& f : files) out << "  " << (target / f.first).string() << "\n";
  out << fmt::format(
      "next:\n"
      "  cmake -S {0} -B {0}/build -DCMAKE_PREFIX_PATH=<pdyn install prefix>\n"
      "  cmake --build {0}/build\n"
      "  ctest --test-dir {0}/build      # pdyn check {1}, the example scene and test_{1}\n"
      "  {2}: {3}\n",
      target.string(), a.name, (target / ("test_" + a.name + ".cpp")).string(),
      test_advice(a.kind));
  return kOk;
}

}  // namespace

SdkCommand add_new_command(CLI::App& app) {
  auto a = std::make_shared<NewArgs>();
  CLI::App* sub = app.add_subcommand(
      "new", "write a new plugin project (CMake, source, README, scene, conformance test)");
  sub->add_option("kind", a->kind,
                  "force, solver, collider, pair (a pair force), bonded (a bonded force), writer "
                  "or constraint")
      ->required()
      ->check(
          CLI::IsMember({"force", "solver", "collider", "pair", "bonded", "writer", "constraint"}));
  sub->add_option("name", a->name, "the plugin's name, [a-z0-9_]+")->required();
  sub->add_option("dir", a->dir, "folder to create (default: ./NAME); must be new or empty");
  add_plugin_path_option(sub, a->plugin_path,
                         "also refuse names of the plugins in this folder (repeatable)");
  return {sub, [a](std::ostream& out, std::ostream& err) { return cmd_new(*a, out, err); }};
}

}  // namespace pdyn::cli
