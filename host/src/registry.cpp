// Plugin discovery and loading with Boost.DLL.
//
// Each library is opened with RTLD_NOW so that a missing symbol is reported
// at discovery, with the library's path, rather than as a crash mid-run. The
// ABI version is read through a plain C function before the C++ descriptor
// is touched: a library built against another kernel may lay out
// PluginDescriptor differently, so nothing else of it is trusted until the
// versions agree.
#include "pdyn/host/registry.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <boost/dll/runtime_symbol_info.hpp>
#include <boost/dll/shared_library.hpp>
#include <cstdlib>
#include <set>

#include "isa_variant.hpp"
#include "pdyn/host/scene_specs.hpp"

namespace pdyn {

namespace fs = std::filesystem;

bool is_valid_plugin_name(std::string_view name) {
  return !name.empty() && std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
  });
}

bool is_valid_param_name(std::string_view name) {
  auto letter = [](char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_'; };
  return !name.empty() && letter(name[0]) && name != "type" &&
         std::all_of(name.begin(), name.end(),
                     [&](char c) { return letter(c) || (c >= '0' && c <= '9'); });
}

namespace {

// "pdyn_force_gravity.so" -> "gravity": what a faulty library probably provides.
std::string name_from_file(const fs::path& file) {
  std::string stem = file.stem().string();
  for (const char* prefix : {"libpdyn_", "pdyn_"}) {
    if (stem.rfind(prefix, 0) == 0) {
      stem = stem.substr(std::char_traits<char>::length(prefix));
      break;
    }
  }
  for (const char* kind : {"force_", "solver_", "collider_", "writer_"}) {
    if (stem.rfind(kind, 0) == 0) return stem.substr(std::char_traits<char>::length(kind));
  }
  return stem;
}

// Boost.DLL reports a failed dlopen() as "...load() failed (dlerror system
// message: FILE: WHY): ERRNO TEXT"; the errno text is unrelated and FILE is
// already in the fault. Keeps WHY ("file too short", "undefined symbol: ...").
std::string load_failure(const std::string& what, const fs::path& file) {
  const std::string tag = "dlerror system message: ";
  auto begin = what.find(tag);
  const auto end = what.rfind("): ");
  if (begin == std::string::npos || end == std::string::npos || end < begin) return what;
  begin += tag.size();
  std::string why = what.substr(begin, end - begin);
  const std::string prefix = file.string() + ": ";
  if (why.rfind(prefix, 0) == 0) why.erase(0, prefix.size());
  return why;
}

// PluginDescriptor as plugins built for ABI 6 lay it out: the same members
// in the same order, without those ABI 7 appended. Its members must be
// exactly ABI 6's (docs/plugins.md, "ABI"); tests/host/registry_test.cpp
// loads a plugin built from ABI 6's headers through it.
struct DescriptorAbi6 {
  PluginKind kind = PluginKind::Force;
  std::string name;
  std::string version;
  std::string description;
  std::vector<ParamSpec> params;
  ForceTraits force_traits;
  SolverTraits solver_traits;
  ForceFactory create_force;
  SolverFactory create_solver;
  ColliderFactory create_collider;
  WriterTraits writer_traits;
  WriterFactory create_writer;
  WriterReader read_back;
};

std::shared_ptr<const PluginDescriptor> upgrade(const DescriptorAbi6& old) {
  auto d = std::make_shared<PluginDescriptor>();
  d->kind = old.kind;
  d->name = old.name;
  d->version = old.version;
  d->description = old.description;
  d->params = old.params;
  d->force_traits = old.force_traits;
  d->solver_traits = old.solver_traits;
  d->create_force = old.create_force;
  d->create_solver = old.create_solver;
  d->create_collider = old.create_collider;
  d->writer_traits = old.writer_traits;
  d->create_writer = old.create_writer;
  d->read_back = old.read_back;
  return d;
}

// Checks what the host relies on before listing a plugin.
std::string descriptor_problem(const PluginDescriptor& d) {
  if (!is_valid_plugin_name(d.name)) {
    return fmt::format(
        "plugin name '{}' is not allowed (expected lower-case letters, digits "
        "and '_', e.g. n_body)",
        d.name);
  }
  const bool has_factory = (d.kind == PluginKind::Force && d.create_force) ||
                           (d.kind == PluginKind::Solver && d.create_solver) ||
                           (d.kind == PluginKind::Collider && d.create_collider) ||
                           (d.kind == PluginKind::Writer && d.create_writer) ||
                           (d.kind == PluginKind::Constraint && d.create_constraint);
  if (!has_factory) return fmt::format("descriptor has no {} factory", kind_name(d.kind));
  std::set<std::string> seen;
  for (const auto& p : d.params) {
    if (!is_valid_param_name(p.name)) {
      return fmt::format(
          "parameter name '{}' is not allowed (expected a letter or '_', then "
          "letters, digits or '_', e.g. G or k_spring; not 'type', which names "
          "the plugin)",
          p.name);
    }
    if (!seen.insert(p.name).second) return fmt::format("parameter '{}' declared twice", p.name);
    if (d.kind == PluginKind::Writer) {
      for (const auto& own : writer_entry_keys()) {
        if (p.name == own.name) {
          return fmt::format(
              "parameter name '{}' is not allowed for a writer (expected a name other than "
              "path, every and fields, which the host reads for every writer)",
              p.name);
        }
      }
    }
    // ParamType's enumerators are in the order of ParamValue's alternatives,
    // so a default of the parameter's own type has the type's index.
    if (p.fallback && p.fallback->index() != static_cast<std::size_t>(p.type)) {
      return fmt::format("default of parameter '{}' is not {}", p.name, describe(p.type));
    }
  }
  return {};
}

}  // namespace

const char* kind_name(PluginKind kind) {
  switch (kind) {
    case PluginKind::Force:
      return "force";
    case PluginKind::Solver:
      return "solver";
    case PluginKind::Collider:
      return "collider";
    case PluginKind::Writer:
      return "writer";
    case PluginKind::Constraint:
      return "constraint";
  }
  return "?";
}

std::string PluginRegistry::folder_problem(const fs::path& dir) {
  std::error_code ec;
  if (fs::is_directory(dir, ec)) return {};
  return fmt::format("'{}' is {} (expected a folder holding plugin libraries pdyn_KIND_NAME.so)",
                     dir.string(), fs::exists(dir, ec) ? "not a folder" : "no such folder");
}

namespace {

// The plugin folder beside the kernel library (this installation's), and
// the one beside the running program; empty where it cannot be found.
fs::path library_folder() {
  boost::dll::fs::error_code ec;
  const fs::path kernel = boost::dll::symbol_location_ptr(&is_valid_plugin_name, ec);
  return ec ? fs::path() : kernel.parent_path() / PDYN_LIB_TO_PLUGINS;
}
fs::path program_folder() {
  boost::dll::fs::error_code ec;
  const fs::path program = boost::dll::program_location(ec);
  return ec ? fs::path() : program.parent_path() / PDYN_BIN_TO_PLUGINS;
}

// Existing folders of `candidates`, canonical where possible, each once.
std::vector<fs::path> existing_once(const std::vector<fs::path>& candidates) {
  std::vector<fs::path> dirs;
  std::set<fs::path> seen;
  for (const auto& c : candidates) {
    std::error_code fec;
    if (c.empty() || !fs::is_directory(c, fec)) continue;
    const fs::path canon = fs::weakly_canonical(c, fec);
    const fs::path key = fec ? c : canon;
    if (seen.insert(key).second) dirs.push_back(key);
  }
  return dirs;
}

}  // namespace

std::vector<fs::path> PluginRegistry::search_path(const std::vector<fs::path>& extra,
                                                  DefaultFolders defaults) {
  std::vector<fs::path> candidates = extra;
  if (const char* env = std::getenv("PDYN_PLUGIN_PATH")) {
    std::string_view s(env);
    while (!s.empty()) {
      const auto colon = s.find(':');
      const auto part = s.substr(0, colon);
      if (!part.empty()) candidates.emplace_back(std::string(part));
      if (colon == std::string_view::npos) break;
      s.remove_prefix(colon + 1);
    }
  }
  candidates.push_back(library_folder());
  if (defaults == DefaultFolders::LibraryAndProgram) candidates.push_back(program_folder());
  return existing_once(candidates);
}

std::vector<fs::path> PluginRegistry::default_folders() {
  return existing_once({library_folder(), program_folder()});
}

bool PluginRegistry::in_default_folder(const fs::path& library) {
  if (!defaults_) defaults_ = default_folders();
  std::error_code ec;
  const fs::path dir = fs::weakly_canonical(isa::home_folder(library), ec);
  return !ec && std::find(defaults_->begin(), defaults_->end(), dir) != defaults_->end();
}

void PluginRegistry::fault(const fs::path& lib, std::string plugin, std::string message) {
  faults_.push_back({lib, std::move(plugin), std::move(message)});
}

// Each library is loaded as its variant for the best ISA level this CPU
// runs, where one was built (isa_variant.hpp); the record names the file
// loaded.
void PluginRegistry::discover(const std::vector<fs::path>& dirs) {
  const std::vector<std::string> levels = isa::usable_levels();
  for (const auto& dir : dirs) {
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) continue;
    searched_.push_back(dir);
    std::vector<fs::path> files;
    for (const auto& entry : fs::directory_iterator(dir, ec)) {
      if (entry.path().extension() == ".so") files.push_back(entry.path());
    }
    std::sort(files.begin(), files.end());
    for (const auto& f : files) load_library(isa::best_variant(f, levels));
  }
}

bool PluginRegistry::load_library(const fs::path& file) {
  const std::string hint = name_from_file(file);
  auto lib = std::make_shared<boost::dll::shared_library>();
  try {
    lib->load(file, boost::dll::load_mode::rtld_now | boost::dll::load_mode::rtld_local);
  } catch (const std::exception& e) {
    fault(file, hint,
          fmt::format("cannot load library: {} (expected a shared library built with "
                      "pdyn_add_plugin against this pdyn)",
                      load_failure(e.what(), file)));
    return false;
  }
  if (!lib->has(kAbiSymbol) || !lib->has(kDescriptorSymbol)) {
    fault(file, hint,
          fmt::format("not a pdyn plugin: it does not export {}() and {}() (use PDYN_PLUGIN)",
                      kAbiSymbol, kDescriptorSymbol));
    return false;
  }
  const std::uint32_t abi = lib->get<std::uint32_t() noexcept>(kAbiSymbol)();
  if (abi < kOldestAbiVersion || abi > kAbiVersion) {
    fault(file, hint,
          fmt::format("plugin ABI version {} is not one this kernel loads (expected {} to {}: "
                      "rebuild the plugin against this pdyn)",
                      abi, kOldestAbiVersion, kAbiVersion));
    return false;
  }
  const PluginDescriptor* d = nullptr;
  std::shared_ptr<const PluginDescriptor> upgraded;
  try {
    if (abi == 6) {
      // An ABI 6 descriptor ends before create_constraint: copy the members
      // it has into a descriptor of this ABI, which the record keeps.
      const auto* old = lib->get<const DescriptorAbi6*()>(kDescriptorSymbol)();
      if (old != nullptr) {
        upgraded = upgrade(*old);
        d = upgraded.get();
      }
    } else {
      d = lib->get<const PluginDescriptor*()>(kDescriptorSymbol)();
    }
  } catch (const std::exception& e) {
    fault(file, hint, fmt::format("descriptor threw: {}", e.what()));
    return false;
  }
  if (d == nullptr) {
    fault(file, hint, "descriptor is null");
    return false;
  }
  if (abi == 6 && d->kind == PluginKind::Constraint) {
    fault(file, hint, "plugin ABI version 6 has no constraint kind (expected ABI 7 or later)");
    return false;
  }
  if (!admit(*d, file, hint, std::static_pointer_cast<void>(lib))) return false;
  plugins_.back().owned_descriptor = std::move(upgraded);
  if (lib->has(kBuildFlagsSymbol)) {
    plugins_.back().optimised =
        (lib->get<std::uint32_t() noexcept>(kBuildFlagsSymbol)() & kBuildOptimised) != 0;
  }
  return true;
}

bool PluginRegistry::add(const PluginDescriptor& descriptor, const fs::path& origin) {
  return admit(descriptor, origin, descriptor.name, nullptr);
}

bool PluginRegistry::admit(const PluginDescriptor& d, const fs::path& file, const std::string& hint,
                           std::shared_ptr<void> handle) {
  if (auto problem = descriptor_problem(d); !problem.empty()) {
    fault(file, is_valid_plugin_name(d.name) ? d.name : hint, problem);
    return false;
  }
  if (const PluginRecord* other = find_any(d.name)) {
    if (isa::home_folder(file) != isa::home_folder(other->library) && in_default_folder(file) &&
        in_default_folder(other->library)) {
      shadowed_.push_back({file, d.name, other->library});
      return false;
    }
    fault(file, d.name,
          fmt::format("plugin '{}' is already provided by {}", d.name, other->library.string()));
    return false;
  }
  plugins_.push_back({&d, file, std::move(handle), std::nullopt, nullptr});
  return true;
}

const PluginRecord* PluginRegistry::find(PluginKind kind, std::string_view name) const {
  for (const auto& r : plugins_) {
    if (r.descriptor->kind == kind && r.descriptor->name == name) return &r;
  }
  return nullptr;
}

const PluginRecord* PluginRegistry::find_any(std::string_view name) const {
  for (const auto& r : plugins_) {
    if (r.descriptor->name == name) return &r;
  }
  return nullptr;
}

void PluginRegistry::require_healthy(std::string_view name) const {
  for (const auto& f : faults_) {
    if (f.plugin == name) {
      throw PluginError(
          fmt::format("{}: plugin '{}': {}", f.library.string(), f.plugin, f.message));
    }
  }
}

std::vector<std::string> PluginRegistry::names(PluginKind kind) const {
  std::vector<std::string> out;
  for (const auto& r : plugins_) {
    if (r.descriptor->kind == kind) out.push_back(r.descriptor->name);
  }
  std::sort(out.begin(), out.end());
  return out;
}

namespace {
// Wraps a plugin-made object so that it keeps its library loaded: the
// deleter runs the object's destructor (code inside the library) and only
// then releases the library handle.
template <class T>
std::shared_ptr<T> keep_loaded(std::unique_ptr<T> obj, const PluginRecord& r) {
  if (!obj) {
    throw PluginError(fmt::format("{}: plugin '{}': factory returned no object", r.library.string(),
                                  r.descriptor->name));
  }
  std::shared_ptr<void> handle = r.handle;
  return std::shared_ptr<T>(obj.release(), [handle](T* p) { delete p; });
}
}  // namespace

std::shared_ptr<Force> PluginRegistry::create_force(const PluginRecord& r, const Params& p,
                                                    const SceneContext& ctx) const {
  return keep_loaded(r.descriptor->create_force(p, ctx), r);
}
std::shared_ptr<Solver> PluginRegistry::create_solver(const PluginRecord& r, const Params& p,
                                                      const SceneContext& ctx) const {
  return keep_loaded(r.descriptor->create_solver(p, ctx), r);
}
std::shared_ptr<Collider> PluginRegistry::create_collider(const PluginRecord& r, const Params& p,
                                                          const SceneContext& ctx) const {
  return keep_loaded(r.descriptor->create_collider(p, ctx), r);
}

std::shared_ptr<Constraint> PluginRegistry::create_constraint(const PluginRecord& r,
                                                              const Params& p,
                                                              const SceneContext& ctx) const {
  return keep_loaded(r.descriptor->create_constraint(p, ctx), r);
}

std::shared_ptr<Writer> create_writer(const PluginRecord& r, const Params& p,
                                      const WriterContext& ctx) {
  return keep_loaded(r.descriptor->create_writer(p, ctx), r);
}

}  // namespace pdyn
