// Plugin discovery and loading: the search order, faults (wrong ABI, a
// library that is not a plugin, a file that is not a library, a duplicate
// name), how scenes and `pdyn plugins` report them, and that plugin-made
// objects keep their library loaded.
//
// The fixture plugins (tests/fixtures/) each sit in a folder of their own:
//   abi/        pdyn_force_abi_broken.so   exports ABI version 999
//   notplugin/  pdyn_force_not_a_plugin.so a shared library without the entry points
//   text/       pdyn_force_text.so         a text file
//   dup/        pdyn_force_gravity.so      a second valid `gravity`
//   push/       pdyn_force_test_push.so    a valid force, test_push
//   construct/  pdyn_force_throwing_factory.so, pdyn_force_throwing_descriptor.so
#include "pdyn/host/registry.hpp"

#include <dlfcn.h>
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>

#include "pdyn/host/assembly.hpp"
#include "pdyn/system.hpp"
#include "pdyn/text.hpp"
#include "pdyn/version.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

namespace fs = std::filesystem;

fs::path real_path(const fs::path& p) { return fs::weakly_canonical(p); }
fs::path fixture(const std::string& folder) {
  return real_path(fs::path(PDYN_FIXTURE_DIR) / folder);
}
fs::path shipped_dir() { return real_path(PDYN_PLUGIN_DIR); }
// The folder a library was discovered in: its own, or for an ISA variant
// (FOLDER/isa/LEVEL/NAME, host/src/isa_variant.hpp) FOLDER.
fs::path home_dir(const fs::path& library) {
  const fs::path level = real_path(library).parent_path();
  return level.parent_path().filename() == "isa" ? level.parent_path().parent_path() : level;
}

// The seven plugins pdyn has shipped from the start (more may be added).
const std::vector<std::pair<PluginKind, std::string>> kSeedPlugins = {
    {PluginKind::Force, "gravity"},   {PluginKind::Force, "drag"},
    {PluginKind::Force, "spring"},    {PluginKind::Solver, "euler"},
    {PluginKind::Solver, "midpoint"}, {PluginKind::Solver, "rk4"},
    {PluginKind::Collider, "plane"},  {PluginKind::Writer, "csv"}};

// Sets (or unsets, for nullopt) an environment variable for one scope.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const std::optional<std::string>& value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    if (value)
      ::setenv(name, value->c_str(), 1);
    else
      ::unsetenv(name);
  }
  ~ScopedEnv() {
    if (old_)
      ::setenv(name_, old_->c_str(), 1);
    else
      ::unsetenv(name_);
  }
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;

 private:
  const char* name_;
  std::optional<std::string> old_;
};

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// A one-particle scene with one force of type `force`, written to a temp file.
fs::path scene_with_force(const std::string& folder, const std::string& force) {
  return test::write_file(test::temp_dir(folder) / "scene.yaml",
                          "simulation: { dt: 0.01, steps: 10 }\n"
                          "particles:\n"
                          "  - { position: [0, 0, 1], mass: 1 }\n"
                          "forces:\n"
                          "  - { type: " +
                              force + " }\n");
}

const PluginFault* fault_for(const PluginRegistry& r, const std::string& plugin) {
  for (const auto& f : r.faults()) {
    if (f.plugin == plugin) return &f;
  }
  return nullptr;
}

// ---------------------------------------------------------------------------
// Discovery

TEST(Registry, ShippedPluginsAreDiscoveredFromTheBuildTree) {
  PluginRegistry r;
  r.discover({PDYN_PLUGIN_DIR});
  for (const auto& f : r.faults()) {
    ADD_FAILURE() << "fault: " << f.library << ": " << f.plugin << ": " << f.message;
  }
  std::size_t files = 0;
  for (const auto& entry : fs::directory_iterator(PDYN_PLUGIN_DIR)) {
    files += entry.path().extension() == ".so";
  }
  EXPECT_EQ(r.plugins().size(), files) << "every library in the plugin folder is a plugin";
  EXPECT_GE(r.plugins().size(), kSeedPlugins.size());
  for (const auto& [kind, name] : kSeedPlugins) {
    const PluginRecord* rec = r.find(kind, name);
    ASSERT_NE(rec, nullptr) << name;
    EXPECT_EQ(rec->descriptor->name, name);
    EXPECT_EQ(home_dir(rec->library), shipped_dir());
    EXPECT_EQ(rec->library.filename().string(),
              std::string("pdyn_") + kind_name(kind) + "_" + name + ".so");
  }
  EXPECT_EQ(r.names(PluginKind::Force).size() + r.names(PluginKind::Solver).size() +
                r.names(PluginKind::Collider).size() + r.names(PluginKind::Writer).size() +
                r.names(PluginKind::Constraint).size(),
            r.plugins().size());
  EXPECT_EQ(r.searched(), std::vector<fs::path>{PDYN_PLUGIN_DIR});
}

TEST(Registry, DefaultSearchPathIsThePluginFolderOfTheBuildTree) {
  ScopedEnv env("PDYN_PLUGIN_PATH", std::nullopt);
  const auto dirs = PluginRegistry::search_path({});
  // Beside the program (bin/../lib/pdyn/plugins) and beside the kernel
  // library (lib/pdyn/plugins): the same folder in the build tree, once.
  EXPECT_EQ(dirs, std::vector<fs::path>{shipped_dir()});

  const auto r = test::pdyn({"plugins", "--json"});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  std::set<std::string> names;
  for (const auto& p : j["plugins"]) {
    names.insert(p["name"].get<std::string>());
    EXPECT_EQ(home_dir(p["library"].get<std::string>()), shipped_dir());
  }
  for (const auto& [kind, name] : kSeedPlugins) EXPECT_TRUE(names.count(name)) << name;
  EXPECT_TRUE(j["faults"].empty()) << j["faults"].dump(2);
}

// Run-time ISA dispatch: with PDYN_ISA=baseline no library is a variant;
// capped at a level, the plugins with variants load from isa/LEVEL/ when
// the CPU runs it (else from a lower level or the baseline), every other
// plugin from the folder itself; a PDYN_ISA naming no level is refused.
TEST(Registry, PdynIsaPicksTheVariantOfALevelOrTheBaseline) {
  ScopedEnv path("PDYN_PLUGIN_PATH", std::nullopt);
  {
    ScopedEnv isa("PDYN_ISA", "baseline");
    PluginRegistry r;
    r.discover({PDYN_PLUGIN_DIR});
    for (const auto& rec : r.plugins()) {
      EXPECT_EQ(real_path(rec.library).parent_path(), shipped_dir()) << rec.library;
    }
  }
  int checked = 0;  // levels built and run by this CPU
  for (const std::string level : {"x86-64-v3", "x86-64-v4"}) {
    ScopedEnv isa("PDYN_ISA", level);
    PluginRegistry r;
    r.discover({PDYN_PLUGIN_DIR});
    const PluginRecord* spring = r.find(PluginKind::Force, "spring");
    ASSERT_NE(spring, nullptr);
    const fs::path variant = shipped_dir() / "isa" / level / spring->library.filename();
    if (!fs::exists(variant)) continue;  // not built (PDYN_ISA_LEVELS)
    const fs::path folder = real_path(spring->library).parent_path();
    if (folder != variant.parent_path()) {
      std::cout << "this CPU does not run " << level << ": spring from " << folder << "\n";
      continue;
    }
    const PluginRecord* gravity = r.find(PluginKind::Force, "gravity");
    ASSERT_NE(gravity, nullptr);
    EXPECT_EQ(real_path(gravity->library).parent_path(), shipped_dir());
    ++checked;
  }
  ScopedEnv isa("PDYN_ISA", "avx2");
  PluginRegistry r;
  try {
    r.discover({PDYN_PLUGIN_DIR});
    ADD_FAILURE() << "PDYN_ISA=avx2 accepted";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(),
                 "PDYN_ISA=avx2: no such level (expected baseline, x86-64-v4, x86-64-v3)");
  }
  if (checked == 0) GTEST_SKIP() << "no ISA variant built, or none this CPU runs";
}

TEST(Registry, SearchPathIsPluginPathThenEnvironmentThenDefaults) {
  const fs::path a = fixture("push"), b = fixture("dup"), c = fixture("abi"), d = fixture("text");
  ScopedEnv env("PDYN_PLUGIN_PATH", c.string() + ":" + d.string());
  const auto dirs = PluginRegistry::search_path({a, b});
  EXPECT_EQ(dirs, (std::vector<fs::path>{a, b, c, d, shipped_dir()}));
}

TEST(Registry, SearchPathDropsMissingRepeatedAndEmptyEntries) {
  const fs::path a = fixture("push"), b = fixture("dup");
  const fs::path missing = test::temp_dir("search-path") / "no-such-folder";
  ScopedEnv env("PDYN_PLUGIN_PATH", "::" + missing.string() + ":" + a.string() + "::" + b.string() +
                                        ":" + shipped_dir().string() + ":");
  // `a` again (spelt differently), a missing folder, the shipped folder early.
  const auto dirs = PluginRegistry::search_path({a / "." / ".." / "push", missing});
  EXPECT_EQ(dirs, (std::vector<fs::path>{a, b, shipped_dir()}));
}

TEST(Registry, PluginsAreRecordedInSearchOrder) {
  PluginRegistry r;
  r.discover({fixture("push"), fixture("dup"), PDYN_PLUGIN_DIR});
  ASSERT_GE(r.plugins().size(), 3u);
  EXPECT_EQ(r.plugins()[0].descriptor->name, "test_push");
  EXPECT_EQ(r.plugins()[1].descriptor->name, "gravity");
  EXPECT_EQ(r.plugins()[1].descriptor->version, "0.0.0-fixture");
  EXPECT_EQ(r.searched(),
            (std::vector<fs::path>{fixture("push"), fixture("dup"), PDYN_PLUGIN_DIR}));
}

// ---------------------------------------------------------------------------
// Duplicates: the first library found provides the plugin; the later one is
// a fault that names both.

void expect_duplicate(const PluginRegistry& r, const fs::path& winner, const fs::path& loser) {
  const PluginRecord* g = r.find(PluginKind::Force, "gravity");
  ASSERT_NE(g, nullptr);
  EXPECT_EQ(real_path(g->library), real_path(winner));
  EXPECT_EQ(std::count_if(r.plugins().begin(), r.plugins().end(),
                          [](const PluginRecord& p) { return p.descriptor->name == "gravity"; }),
            1);
  const PluginFault* f = fault_for(r, "gravity");
  ASSERT_NE(f, nullptr);
  EXPECT_EQ(real_path(f->library), real_path(loser));
  EXPECT_TRUE(contains(f->message, winner.string())) << f->message;
  EXPECT_TRUE(contains(f->message, "already provided")) << f->message;
}

TEST(Registry, DuplicateNameIsAFaultAndTheFirstFoundWins) {
  const fs::path fixture_lib = fixture("dup") / "pdyn_force_gravity.so";
  const fs::path shipped_lib = shipped_dir() / "pdyn_force_gravity.so";
  {
    ScopedEnv env("PDYN_PLUGIN_PATH", std::nullopt);
    PluginRegistry r;
    r.discover(PluginRegistry::search_path({fixture("dup")}));  // --plugin-path first
    expect_duplicate(r, fixture_lib, shipped_lib);
  }
  {
    ScopedEnv env("PDYN_PLUGIN_PATH", fixture("dup").string());  // before the default folders
    PluginRegistry r;
    r.discover(PluginRegistry::search_path({}));
    expect_duplicate(r, fixture_lib, shipped_lib);
  }
  {
    ScopedEnv env("PDYN_PLUGIN_PATH", fixture("dup").string());  // after --plugin-path
    PluginRegistry r;
    r.discover(PluginRegistry::search_path({shipped_dir()}));
    expect_duplicate(r, shipped_lib, fixture_lib);
  }
}

TEST(Registry, DuplicateIsListedByPluginsWithBothPaths) {
  ScopedEnv env("PDYN_PLUGIN_PATH", std::nullopt);
  const auto r = test::pdyn({"plugins", "--plugin-path", fixture("dup").string()});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(contains(r.out, "0.0.0-fixture")) << r.out;
  EXPECT_TRUE(contains(r.out, "error: " + (shipped_dir() / "pdyn_force_gravity.so").string() +
                                  ": plugin 'gravity': plugin 'gravity' is already provided by " +
                                  (fixture("dup") / "pdyn_force_gravity.so").string()))
      << r.out;
}

// A program run as a user would (a copy of the real pdyn, PDYN_BIN, in a
// folder of its own): its exit status, stdout and stderr.
test::CommandResult run_program(const fs::path& program, const std::string& args) {
  const fs::path err = test::temp_dir("program-stderr") / "err.txt";
  const std::string cmd =
      "env -u PDYN_PLUGIN_PATH '" + program.string() + "' " + args + " 2>'" + err.string() + "'";
  test::CommandResult r;
  FILE* pipe = popen(cmd.c_str(), "r");
  if (!pipe) return r;
  char buf[4096];
  for (std::size_t n; (n = fread(buf, 1, sizeof buf, pipe)) > 0;) r.out.append(buf, n);
  const int status = pclose(pipe);
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.err = test::read_bytes(err);
  return r;
}

// A pdyn program in `root`/bin whose own plugin folder (bin/../lib/pdyn/
// plugins) is not its libraries' (those of the build tree): two
// installations side by side. Returns the program.
fs::path program_beside_another_install(const fs::path& root) {
  fs::create_directories(root / "bin");
  fs::create_directories(root / "lib/pdyn/plugins");
  fs::copy_file(PDYN_BIN, root / "bin/pdyn");
  return root / "bin/pdyn";
}

// Two installations side by side (issue 42): the program's own folder holds
// another gravity. The libraries' folder comes first and wins; the other
// library is listed as shadowed, not a fault, and a scene using gravity
// validates without a word.
TEST(Registry, APluginInTwoDefaultFoldersIsShadowedNotAFault) {
  const fs::path root = real_path(test::temp_dir("two-installs"));
  const fs::path program = program_beside_another_install(root);
  const fs::path other = root / "lib/pdyn/plugins/pdyn_force_gravity.so";
  fs::copy_file(fixture("dup") / "pdyn_force_gravity.so", other);
  const fs::path ours = shipped_dir() / "pdyn_force_gravity.so";

  const auto r = run_program(program, "plugins --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(j["faults"].empty()) << j["faults"].dump(2);
  ASSERT_EQ(j["shadowed"].size(), 1u) << j["shadowed"].dump(2);
  EXPECT_EQ(j["shadowed"][0]["library"], other.string());
  EXPECT_EQ(j["shadowed"][0]["plugin"], "gravity");
  EXPECT_EQ(j["shadowed"][0]["by"], ours.string());
  EXPECT_EQ(j["searched"],
            (nlohmann::json{shipped_dir().string(), (root / "lib/pdyn/plugins").string()}));
  for (const auto& p : j["plugins"]) {
    if (p["name"] == "gravity") {
      EXPECT_EQ(p["library"], ours.string());
    }
  }
  const auto text = run_program(program, "plugins");
  EXPECT_TRUE(contains(text.out, "shadowed: " + other.string() +
                                     ": plugin 'gravity' (provided by " + ours.string() +
                                     ", an earlier default folder)"))
      << text.out;
  const fs::path scene = scene_with_force("two-installs-scene", "gravity");
  const auto v = run_program(program, "validate '" + scene.string() + "'");
  EXPECT_EQ(v.status, 0) << v.err;
  EXPECT_EQ(v.err, "");
}

// Within one folder, two libraries of one name stay a fault, default
// folder or not.
TEST(Registry, TwoLibrariesOfOneNameInOneDefaultFolderStayAFault) {
  const fs::path root = real_path(test::temp_dir("one-install-twice"));
  const fs::path program = program_beside_another_install(root);
  const fs::path dir = root / "lib/pdyn/plugins";
  fs::copy_file(fixture("push") / "pdyn_force_test_push.so", dir / "pdyn_force_test_push.so");
  fs::copy_file(fixture("push") / "pdyn_force_test_push.so", dir / "pdyn_force_test_push2.so");
  const auto r = run_program(program, "plugins --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(j["shadowed"].empty()) << j.dump(2);
  ASSERT_EQ(j["faults"].size(), 1u) << j.dump(2);
  EXPECT_EQ(j["faults"][0]["library"], (dir / "pdyn_force_test_push2.so").string());
  EXPECT_EQ(j["faults"][0]["message"], "plugin 'test_push' is already provided by " +
                                           (dir / "pdyn_force_test_push.so").string());
}

// registry.hpp: require_healthy() refuses a plugin that two libraries
// provide, so a scene using the duplicated name is a plugin fault (exit 3)
// that names both libraries, rather than silently running either.
TEST(Registry, SceneUsingADuplicatedPluginNamesBothLibraries) {
  ScopedEnv env("PDYN_PLUGIN_PATH", std::nullopt);
  const fs::path scene = scene_with_force("dup-scene", "gravity");
  const auto r = test::pdyn({"validate", scene.string(), "--plugin-path", fixture("dup").string()});
  EXPECT_EQ(r.status, 3) << r.err;
  const auto lines = test::split_lines(r.err);
  ASSERT_FALSE(lines.empty());
  EXPECT_TRUE(contains(lines.back(), (shipped_dir() / "pdyn_force_gravity.so").string()))
      << lines.back();
  EXPECT_TRUE(contains(lines.back(), (fixture("dup") / "pdyn_force_gravity.so").string()))
      << lines.back();
}

// ---------------------------------------------------------------------------
// Libraries that cannot be used

TEST(Registry, WrongAbiIsRefusedWithBothVersions) {
  PluginRegistry r;
  // The fixture's descriptor aborts if called: only the version may be read.
  r.discover({fixture("abi")});
  EXPECT_TRUE(r.plugins().empty());
  ASSERT_EQ(r.faults().size(), 1u);
  const PluginFault& f = r.faults()[0];
  EXPECT_EQ(real_path(f.library), fixture("abi") / "pdyn_force_abi_broken.so");
  EXPECT_EQ(f.plugin, "abi_broken") << "the name comes from pdyn_<kind>_<name>.so";
  EXPECT_TRUE(contains(f.message, "999")) << f.message;
  EXPECT_TRUE(contains(f.message, fmt::format("expected {} to {}", kOldestAbiVersion, kAbiVersion)))
      << f.message;
  EXPECT_THROW(r.require_healthy("abi_broken"), PluginError);
  EXPECT_NO_THROW(r.require_healthy("gravity"));
}

TEST(Registry, LibraryWithoutEntryPointsIsNotAPlugin) {
  PluginRegistry r;
  r.discover({fixture("notplugin")});
  EXPECT_TRUE(r.plugins().empty());
  ASSERT_EQ(r.faults().size(), 1u);
  EXPECT_EQ(r.faults()[0].plugin, "not_a_plugin");
  EXPECT_TRUE(contains(r.faults()[0].message, "not a pdyn plugin")) << r.faults()[0].message;
  EXPECT_TRUE(contains(r.faults()[0].message, kAbiSymbol)) << r.faults()[0].message;
}

TEST(Registry, FileThatIsNotALibraryIsAFault) {
  PluginRegistry r;
  r.discover({fixture("text")});
  EXPECT_TRUE(r.plugins().empty());
  ASSERT_EQ(r.faults().size(), 1u);
  const PluginFault& f = r.faults()[0];
  EXPECT_EQ(f.plugin, "text");
  EXPECT_EQ(f.message.rfind("cannot load library: ", 0), 0u) << f.message;
  // The file is named once, in the fault's library, not again in the message.
  EXPECT_FALSE(contains(f.message, f.library.string())) << f.message;
  EXPECT_FALSE(r.load_library(fixture("text") / "pdyn_force_text.so"));
  EXPECT_EQ(r.faults().size(), 2u);
}

// A broken library that a scene does not use is only a warning.
TEST(Registry, UnusedBrokenLibrariesOnlyWarn) {
  ScopedEnv env("PDYN_PLUGIN_PATH", std::nullopt);
  const fs::path scene = scene_with_force("unused-broken", "gravity");
  const auto r = test::pdyn({"validate", scene.string(), "--plugin-path", fixture("abi").string(),
                             "--plugin-path", fixture("notplugin").string(), "--plugin-path",
                             fixture("text").string()});
  EXPECT_EQ(r.status, 0) << r.err;
  const auto lines = test::split_lines(r.err);
  ASSERT_EQ(lines.size(), 3u) << r.err;
  for (const auto& l : lines) EXPECT_EQ(l.rfind("pdyn: warning: ", 0), 0u) << l;
}

TEST(Registry, SceneUsingAPluginWithTheWrongAbiExitsThree) {
  ScopedEnv env("PDYN_PLUGIN_PATH", std::nullopt);
  const fs::path scene = scene_with_force("abi-scene", "abi_broken");
  const fs::path lib = fixture("abi") / "pdyn_force_abi_broken.so";
  for (const char* command : {"validate", "run"}) {
    const auto r = test::pdyn({command, scene.string(), "--plugin-path", fixture("abi").string()});
    EXPECT_EQ(r.status, 3) << command << "\n" << r.err;
    const auto lines = test::split_lines(r.err);
    ASSERT_FALSE(lines.empty()) << command;
    const std::string& error = lines.back();
    EXPECT_EQ(error.rfind(lib.string() + ": plugin 'abi_broken': ", 0), 0u) << error;
    EXPECT_TRUE(contains(error, "plugin ABI version 999")) << error;
    EXPECT_TRUE(contains(error, fmt::format("is not one this kernel loads (expected {} to {}",
                                            kOldestAbiVersion, kAbiVersion)))
        << error;
  }
}

TEST(Registry, SceneUsingAFileThatIsNotALibraryExitsThree) {
  ScopedEnv env("PDYN_PLUGIN_PATH", std::nullopt);
  const fs::path scene = scene_with_force("text-scene", "text");
  const auto r =
      test::pdyn({"validate", scene.string(), "--plugin-path", fixture("text").string()});
  EXPECT_EQ(r.status, 3) << r.err;
  EXPECT_TRUE(contains(
      test::split_lines(r.err).back(),
      (fixture("text") / "pdyn_force_text.so").string() + ": plugin 'text': cannot load library: "))
      << r.err;
}

TEST(Registry, DescribingABrokenPluginExitsThree) {
  ScopedEnv env("PDYN_PLUGIN_PATH", std::nullopt);
  const auto r =
      test::pdyn({"plugins", "describe", "abi_broken", "--plugin-path", fixture("abi").string()});
  EXPECT_EQ(r.status, 3) << r.err;
  EXPECT_TRUE(contains(r.err, "999")) << r.err;
}

TEST(Registry, UnknownPluginInASceneListsTheAvailableOnes) {
  ScopedEnv env("PDYN_PLUGIN_PATH", std::nullopt);
  const fs::path scene = scene_with_force("unknown-plugin", "tset_push");
  const auto r =
      test::pdyn({"validate", scene.string(), "--plugin-path", fixture("push").string()});
  EXPECT_EQ(r.status, 2) << r.err;
  const auto lines = test::split_lines(r.err);
  ASSERT_EQ(lines.size(), 1u) << r.err;
  EXPECT_EQ(lines[0].rfind(scene.string() + ":5:13: forces[0].type: unknown force type 'tset_push' "
                                            "(did you mean 'test_push'? expected one of: ",
                           0),
            0u)
      << lines[0];
  PluginRegistry reg;
  reg.discover({fixture("push"), PDYN_PLUGIN_DIR});
  EXPECT_TRUE(contains(lines[0], join(reg.names(PluginKind::Force)) + ")")) << lines[0];
  const auto list = lines[0].find("expected one of: ");
  ASSERT_NE(list, std::string::npos);
  EXPECT_TRUE(contains(lines[0].substr(list), "test_push")) << "the fixture is offered too";
}

TEST(Registry, FixturePluginIsUsableFromItsFolder) {
  ScopedEnv env("PDYN_PLUGIN_PATH", fixture("push").string());
  const fs::path scene = scene_with_force("push-scene", "test_push");
  const auto r = test::pdyn({"validate", scene.string()});
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.err, "");
}

// ---------------------------------------------------------------------------
// pdyn plugins --json

TEST(Registry, PluginsJsonListsPluginsFaultsAndFolders) {
  ScopedEnv env("PDYN_PLUGIN_PATH", fixture("text").string());
  const auto r =
      test::pdyn({"plugins", "--json", "--plugin-path", fixture("push").string(), "--plugin-path",
                  fixture("abi").string(), "--plugin-path", fixture("notplugin").string(),
                  "--plugin-path", fixture("dup").string()});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.err, "");
  nlohmann::json j;
  ASSERT_NO_THROW(j = nlohmann::json::parse(r.out)) << r.out;
  ASSERT_TRUE(j["plugins"].is_array());
  ASSERT_TRUE(j["faults"].is_array());
  ASSERT_TRUE(j["searched"].is_array());

  std::map<std::string, nlohmann::json> plugins;
  for (const auto& p : j["plugins"]) {
    for (const char* key : {"kind", "name", "version", "description", "library", "params"}) {
      EXPECT_TRUE(p.contains(key)) << key << " in " << p.dump();
    }
    EXPECT_TRUE(plugins.emplace(p["name"].get<std::string>(), p).second) << "listed twice: " << p;
  }
  for (const auto& [kind, name] : kSeedPlugins) {
    ASSERT_TRUE(plugins.count(name)) << name;
    EXPECT_EQ(plugins[name]["kind"], kind_name(kind));
  }
  ASSERT_TRUE(plugins.count("test_push"));
  EXPECT_EQ(plugins["test_push"]["params"][0]["name"], "f");
  EXPECT_EQ(plugins["gravity"]["version"], "0.0.0-fixture") << "the first gravity found";

  std::map<std::string, nlohmann::json> faults;
  for (const auto& f : j["faults"]) {
    for (const char* key : {"library", "plugin", "message"}) {
      EXPECT_TRUE(f[key].is_string()) << key << " in " << f.dump();
    }
    faults[f["plugin"].get<std::string>()] = f;
  }
  EXPECT_EQ(faults.size(), 4u) << j["faults"].dump(2);
  ASSERT_TRUE(faults.count("abi_broken"));
  EXPECT_EQ(faults["abi_broken"]["library"],
            (fixture("abi") / "pdyn_force_abi_broken.so").string());
  EXPECT_TRUE(contains(faults["abi_broken"]["message"], "999"));
  ASSERT_TRUE(faults.count("not_a_plugin"));
  ASSERT_TRUE(faults.count("text"));
  ASSERT_TRUE(faults.count("gravity"));
  EXPECT_EQ(faults["gravity"]["library"], (shipped_dir() / "pdyn_force_gravity.so").string());

  std::vector<std::string> searched;
  for (const auto& s : j["searched"]) searched.push_back(s.get<std::string>());
  EXPECT_EQ(searched,
            (std::vector<std::string>{fixture("push").string(), fixture("abi").string(),
                                      fixture("notplugin").string(), fixture("dup").string(),
                                      fixture("text").string(), shipped_dir().string()}));
}

// ---------------------------------------------------------------------------
// Lifetime

// True if the library at `path` is loaded in this process (RTLD_NOLOAD
// never loads it, but does take a reference when it is: released at once).
bool is_loaded(const fs::path& path) {
  void* h = ::dlopen(path.c_str(), RTLD_NOW | RTLD_NOLOAD);
  if (h) ::dlclose(h);
  return h != nullptr;
}

TEST(Registry, CreatedObjectsKeepTheirLibraryLoaded) {
  const fs::path lib = fixture("push") / "pdyn_force_test_push.so";
  ASSERT_FALSE(is_loaded(lib)) << "another test left the fixture loaded";
  System sys;
  SystemAssembly(sys).add_particle(Vec3(0, 0, 0), Vec3::Zero(), 1.0);
  SystemAssembly(sys).add_particle(Vec3(1, 0, 0), Vec3::Zero(), 2.0);
  std::shared_ptr<Force> force;
  {
    auto registry = std::make_unique<PluginRegistry>();
    registry->discover({fixture("push")});
    const PluginRecord* rec = registry->find(PluginKind::Force, "test_push");
    ASSERT_NE(rec, nullptr);
    Params params;
    params.set("f", Vec3(1.5, -2, 0.25));
    force = registry->create_force(*rec, params, SceneContext{sys.view(), nullptr});
    ASSERT_TRUE(force);
    registry.reset();  // the registry and its handles are gone
  }
  ASSERT_TRUE(is_loaded(lib)) << "the force must keep its library loaded";
  Matrix3X f = Matrix3X::Zero(3, 2);
  force->add_forces(sys.view(), f);  // code inside the library
  EXPECT_EQ(f.col(0), Vec3(1.5, -2, 0.25));
  EXPECT_EQ(f.col(1), Vec3(1.5, -2, 0.25));
  std::shared_ptr<Force> copy = force;
  force.reset();
  EXPECT_TRUE(is_loaded(lib)) << "a copy still holds it";
  copy.reset();  // runs the destructor (library code), then releases the library
  EXPECT_FALSE(is_loaded(lib)) << "the last object released its library";
}

// The same through a scene: the system's force objects outlive the registry.
TEST(Registry, SceneObjectsOutliveTheRegistry) {
  std::optional<Scene> scene;
  {
    PluginRegistry registry;
    registry.discover({fixture("push"), PDYN_PLUGIN_DIR});
    scene.emplace(
        load_scene_text("simulation: { dt: 0.1, steps: 1 }\n"
                        "particles:\n"
                        "  - { position: [0, 0, 0], mass: 2 }\n"
                        "forces:\n"
                        "  - { type: test_push, f: [4, 0, 0] }\n",
                        "push.yaml", registry));
  }
  Eigen::VectorXd dydt(6);
  scene->system->derivative(dydt);
  EXPECT_EQ(dydt(3), 2.0);  // a = f / m
}

// ---- the rest of the bad libraries: missing, throwing descriptor, throwing
// factory, and descriptors registered in memory (the conformance kit's way) ----

TEST(Registry, MissingLibraryIsOneLineNamingItsPath) {
  const std::string lib = "/nonexistent/pdyn_force_ghost.so";
  const auto r = test::pdyn({"check", lib});
  EXPECT_EQ(r.status, 3) << r.err;
  const auto lines = test::split_lines(r.err);
  ASSERT_EQ(lines.size(), 1u) << r.err;
  EXPECT_EQ(lines[0].rfind("pdyn: " + lib + ": plugin 'ghost': cannot load library: ", 0), 0u)
      << r.err;
}

TEST(Registry, ThrowingDescriptorIsAFaultNotACrash) {
  ScopedEnv env("PDYN_PLUGIN_PATH", std::nullopt);
  PluginRegistry r;
  r.discover({fixture("construct")});
  const PluginFault* f = fault_for(r, "throwing_descriptor");
  ASSERT_NE(f, nullptr);
  EXPECT_EQ(real_path(f->library), fixture("construct") / "pdyn_force_throwing_descriptor.so");
  EXPECT_EQ(f->message, "descriptor threw: fixture descriptor failure");
  const fs::path scene = scene_with_force("descriptor-scene", "throwing_descriptor");
  const auto res =
      test::pdyn({"run", scene.string(), "--plugin-path", fixture("construct").string()});
  EXPECT_EQ(res.status, 3) << res.err;
  const std::string error = test::split_lines(res.err).back();
  EXPECT_EQ(error.rfind((fixture("construct") / "pdyn_force_throwing_descriptor.so").string() +
                            ": plugin 'throwing_descriptor': descriptor threw: ",
                        0),
            0u)
      << res.err;
}

TEST(Registry, ThrowingFactoryRefusesTheSceneNamingPluginAndLibrary) {
  ScopedEnv env("PDYN_PLUGIN_PATH", std::nullopt);
  const fs::path scene = scene_with_force("factory-scene", "throwing_factory");
  const auto res =
      test::pdyn({"run", scene.string(), "--plugin-path", fixture("construct").string()});
  EXPECT_EQ(res.status, 2) << res.err;
  std::vector<std::string> errors;
  for (const auto& l : test::split_lines(res.err)) {
    if (l.rfind("pdyn: warning: ", 0) != 0) errors.push_back(l);
  }
  ASSERT_EQ(errors.size(), 1u) << res.err;
  EXPECT_TRUE(
      contains(errors[0], scene.string() + ":5:5: forces[0]: plugin 'throwing_factory' (" +
                              (fixture("construct") / "pdyn_force_throwing_factory.so").string() +
                              ") refused its parameters: fixture constructor failure"))
      << errors[0];
}

TEST(Registry, DescriptorsInMemoryGetTheSameChecks) {
  PluginRegistry r;
  PluginDescriptor d;
  d.kind = PluginKind::Force;
  d.name = "in_memory";
  d.version = "1";
  EXPECT_FALSE(r.add(d, "(test)")) << "no factory";
  EXPECT_TRUE(contains(r.faults().back().message, "no force factory"));
  d.create_force = [](const Params&, const SceneContext&) -> std::unique_ptr<Force> {
    return nullptr;
  };
  ASSERT_TRUE(r.add(d, "(test)"));
  ASSERT_NE(r.find(PluginKind::Force, "in_memory"), nullptr);
  EXPECT_FALSE(r.add(d, "(again)"));
  EXPECT_EQ(r.faults().back().message, "plugin 'in_memory' is already provided by (test)");
}

}  // namespace
}  // namespace pdyn
