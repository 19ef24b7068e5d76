// The plugin registry: finds plugin libraries, reads their descriptors and
// creates plugin objects by (kind, name). Host-side; plugins never see it.
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "pdyn/host/export.hpp"
#include "pdyn/plugin.hpp"

namespace pdyn {

/// One plugin found on the search path.
struct PDYN_HOST_API PluginRecord {
  const PluginDescriptor* descriptor = nullptr;
  std::filesystem::path library;
  std::shared_ptr<void> handle;  // the loaded library; every created object holds a copy
  /// Whether the library was compiled with optimisation; unknown for
  /// libraries built before PDYN_PLUGIN recorded it, and for built-ins.
  std::optional<bool> optimised;
  /// For a plugin built for an older ABI: the descriptor the registry made
  /// from its own (`descriptor` points to it).
  std::shared_ptr<const PluginDescriptor> owned_descriptor;
};

/// A library on the search path that could not be used.
struct PDYN_HOST_API PluginFault {
  std::filesystem::path library;
  std::string plugin;   // the plugin's name, or the name its file suggests
  std::string message;  // one line: what is wrong
};

/// A plugin that a library in a later default folder also provides: the
/// earlier folder's library wins, and `pdyn plugins` lists this one.
struct PDYN_HOST_API PluginShadow {
  std::filesystem::path library;  // the library not loaded
  std::string plugin;
  std::filesystem::path by;  // the library that provides the plugin
};

/// Which default folders a host searches after the user's: the plugin
/// folder of this pdyn's own installation (beside the kernel library)
/// always; the one beside the running program only for pdyn's own programs.
/// An embedding program (python3 importing pdyn, a user's executable) is no
/// part of any pdyn installation, and the folder beside it may belong to
/// another one (a build tree's module on a machine with the packages too).
enum class DefaultFolders { Library, LibraryAndProgram };

class PDYN_HOST_API PluginRegistry {
 public:
  /// The search path, in order: `extra` (--plugin-path), the directories in
  /// $PDYN_PLUGIN_PATH (':'-separated), then the default folders: the plugin
  /// folder beside the kernel library, and, with
  /// DefaultFolders::LibraryAndProgram, the one beside the running program
  /// (build tree and install tree alike). Duplicates and missing folders are
  /// dropped.
  static std::vector<std::filesystem::path> search_path(
      const std::vector<std::filesystem::path>& extra,
      DefaultFolders defaults = DefaultFolders::Library);
  /// The default folders (both kinds), canonical, that exist. A plugin
  /// found in two of them comes from the first searched and the other is
  /// listed in shadowed(), not a fault: two installations side by side are
  /// no user's mistake. Within one folder, and between a user's folder and
  /// any other, a second library for one name stays a fault.
  static std::vector<std::filesystem::path> default_folders();
  /// Why `dir` cannot be a folder a user names for plugins (`pdyn ...
  /// --plugin-path`, Python's plugin_path=): "'DIR' is no such folder
  /// (expected ...)", or "" if it is a folder. search_path() drops missing
  /// folders silently; a folder the user typed is checked with this first.
  static std::string folder_problem(const std::filesystem::path& dir);

  /// Loads every `*.so` in `dirs` (in order, files sorted by name) and
  /// records its plugin, or a fault. Never throws for a bad library.
  void discover(const std::vector<std::filesystem::path>& dirs);
  /// Loads one library file; returns false and records a fault on failure.
  bool load_library(const std::filesystem::path& file);
  /// Registers a descriptor that is already in memory (the conformance kit
  /// feeds the plugin under test to the scene loader this way), with the
  /// same checks as a loaded library; `origin` names it in messages. The
  /// descriptor must outlive the registry. Returns false and records a fault
  /// if it is refused.
  bool add(const PluginDescriptor& descriptor, const std::filesystem::path& origin);

  /// The plugin of that kind and name, or nullptr.
  const PluginRecord* find(PluginKind kind, std::string_view name) const;
  /// The plugin of that name, whatever its kind, or nullptr.
  const PluginRecord* find_any(std::string_view name) const;
  /// Throws PluginError if a fault concerns the plugin `name` (its library
  /// failed to load, or two libraries provide it).
  void require_healthy(std::string_view name) const;

  const std::vector<PluginRecord>& plugins() const noexcept { return plugins_; }
  const std::vector<PluginFault>& faults() const noexcept { return faults_; }
  const std::vector<PluginShadow>& shadowed() const noexcept { return shadowed_; }
  const std::vector<std::filesystem::path>& searched() const noexcept { return searched_; }
  /// Sorted names of the plugins of one kind.
  std::vector<std::string> names(PluginKind kind) const;

  /// Create objects. They keep their library loaded for as long as they live.
  std::shared_ptr<Force> create_force(const PluginRecord& r, const Params& p,
                                      const SceneContext& ctx) const;
  std::shared_ptr<Solver> create_solver(const PluginRecord& r, const Params& p,
                                        const SceneContext& ctx) const;
  std::shared_ptr<Collider> create_collider(const PluginRecord& r, const Params& p,
                                            const SceneContext& ctx) const;
  std::shared_ptr<Constraint> create_constraint(const PluginRecord& r, const Params& p,
                                                const SceneContext& ctx) const;

 private:
  void fault(const std::filesystem::path& lib, std::string plugin, std::string message);
  // The checks shared by load_library() and add(), then the listing.
  bool admit(const PluginDescriptor& d, const std::filesystem::path& file, const std::string& hint,
             std::shared_ptr<void> handle);
  bool in_default_folder(const std::filesystem::path& library);
  std::optional<std::vector<std::filesystem::path>> defaults_;  // default_folders(), once
  std::vector<PluginRecord> plugins_;
  std::vector<PluginFault> faults_;
  std::vector<PluginShadow> shadowed_;
  std::vector<std::filesystem::path> searched_;
};

/// Creates a writer of a scene's output list (the runner does, when a run
/// starts). It keeps its library loaded for as long as it lives.
PDYN_HOST_API std::shared_ptr<Writer> create_writer(const PluginRecord& r, const Params& p,
                                                    const WriterContext& ctx);

/// True for names of the form [a-z0-9_]+.
PDYN_HOST_API bool is_valid_plugin_name(std::string_view name);
/// True for parameter names: [A-Za-z_][A-Za-z0-9_]*, except "type" (see ParamSpec::name).
PDYN_HOST_API bool is_valid_param_name(std::string_view name);

}  // namespace pdyn
