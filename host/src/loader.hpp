// The scene loader's insides, shared by its source files (private to the
// host library): the Loader, which reads one scene, and the helpers its
// files share. scene_loader.cpp assembles the scene from the sections;
// yaml_reader.cpp holds the generic YAML-to-parameters reader and the
// diagnostics; overrides.cpp applies --set; scene_specs.cpp declares the
// built-in sections; the builders (grid included) are in scene_builders.cpp
// and grid_builder.cpp, behind BuilderHost.
#pragma once

#include <yaml-cpp/yaml.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "import_files.hpp"
#include "pdyn/domain.hpp"
#include "pdyn/host/resolve.hpp"
#include "pdyn/host/scene.hpp"
#include "pdyn/host/velocities.hpp"
#include "scene_builders.hpp"
#include "written_paths.hpp"

namespace pdyn::loading {

namespace fs = std::filesystem;

std::vector<std::string> spec_names(const std::vector<ParamSpec>& specs);
/// A value as the user wrote it, for a message (see yaml_reader.cpp).
std::string shown(const YAML::Node& n);
/// What yaml-cpp's terse parser messages usually mean, as the expectation.
std::string yaml_hint(const std::string& text, const YAML::ParserException& e);

/// An unclosed '{' or '[' (0-based line and column, like YAML::Mark).
struct OpenBracket {
  char bracket;
  int line, column;
};
/// The innermost '{' or '[' still open where the parser stopped at `stop`,
/// if it was opened on an earlier line.
std::optional<OpenBracket> unclosed_flow(const std::string& text, const YAML::Mark& stop);

// One entry of `particles:` and the ids it made: where a problem with one
// of its particles is reported.
struct ParticleEntry {
  Index first, end;  // ids first .. end - 1
  YAML::Node node;   // the single particle's position, the builder, the file name
  std::string path;  // "particles[2].grid"
};

// A queued force or collider: created once all particles exist.
// Its move assignment copies a YAML::Node (yaml-cpp's has no move), which may
// throw bad_alloc, as any copy.
// NOLINTNEXTLINE(bugprone-exception-escape)
struct PendingPlugin {
  const PluginRecord* record;
  Params params;
  YAML::Node node;
  std::string path;
  double compliance = 0.0;  // a constraint's `compliance` key (0 = rigid)
};

/// Why `force` (a scene object labelled `label`, from `library`) cannot be
/// given special bonds: a pair force built before them. Empty otherwise.
std::string special_bonds_refusal(const Force& force, const std::string& label,
                                  const fs::path& library);

class Loader final : public BuilderHost {
 public:
  Loader(std::string file, const PluginRegistry& registry, std::vector<Override> overrides)
      : file_(std::move(file)), registry_(registry), overrides_(std::move(overrides)) {}

  Scene load(const std::string& text);
  /// Adds the plugin object described by `text` (one item of `forces:` or
  /// `colliders:`, or a `solver:` mapping, as YAML) to the assembled `scene`,
  /// checked like a scene's; locations name the file only (see add_plugin).
  std::string add_to(Scene& scene, PluginKind kind, const std::string& text);

 private:
  // ---- diagnostics ----
  std::string where(const YAML::Node& at, const std::string& path) const;
  void error(const YAML::Node& at, const std::string& path, std::string message) override;
  [[noreturn]] void fail();

  // ---- generic readers ----
  bool check_map(const YAML::Node& n, const std::string& path, const char* what) override;
  bool check_plugin_map(const YAML::Node& n, const std::string& path, PluginKind kind);
  void check_keys(const YAML::Node& map, const std::string& path,
                  const std::vector<std::string>& allowed);
  std::optional<ParamValue> read_value(const YAML::Node& n, const std::string& path,
                                       const ParamSpec& spec, Index n_particles);
  std::optional<double> read_number(const YAML::Node& n, const std::string& path,
                                    const ParamSpec& spec);
  std::optional<ParamValue> read_boolean(const YAML::Node& n, const std::string& path,
                                         const ParamSpec& spec);
  std::optional<ParamValue> read_named_reals(const YAML::Node& n, const std::string& path,
                                             const ParamSpec& spec);
  template <class List, class ReadOne>
  std::optional<List> read_list(const YAML::Node& n, const std::string& path, const ParamSpec& spec,
                                ReadOne&& read_one);
  std::optional<ParamValue> read_integer_list(const YAML::Node& n, const std::string& path,
                                              const ParamSpec& spec);
  std::optional<std::int64_t> read_integer(const YAML::Node& n, const std::string& path,
                                           const ParamSpec& spec);
  std::optional<Index> read_index(const YAML::Node& n, const std::string& path, Index n_particles);
  std::optional<Vec3> read_vec3(const YAML::Node& n, const std::string& path,
                                const ParamSpec& spec);
  template <std::size_t K>
  std::optional<std::vector<std::array<Index, K>>> read_tuples(const YAML::Node& n,
                                                               const std::string& path,
                                                               Index n_particles);
  /// `pairs: { file: polymer.data }` (triples, quads): a section of a data
  /// file the scene's particles came from (scene_topology.cpp).
  template <std::size_t K>
  std::optional<std::vector<std::array<Index, K>>> read_data_terms(const YAML::Node& n,
                                                                   const std::string& path);
  /// The LAMMPS types `types:` selects of a data file's section (empty: all).
  std::optional<std::set<long long>> selected_types(const YAML::Node& n, const std::string& path,
                                                    const import_files::Imported::Terms& terms,
                                                    const std::string& file);
  /// After read_params read a term list from a data file: its types as the
  /// plugin's `types`, or the reason they cannot be.
  void apply_data_types(const YAML::Node& map, const std::string& path,
                        const std::vector<ParamSpec>& specs, Params& given);
  /// Warns about each data file's topology section that no force or
  /// constraint took.
  void warn_unused_topology();
  /// Reads the keys of `map` described by `specs`; `extra` keys are allowed
  /// and left to the caller. Index-typed values are checked against
  /// n_particles when it is >= 0.
  void locate(const YAML::Node& map, const std::string& path, const ParamSpec& spec,
              const ParamProblem& problem);
  std::optional<Params> read_params(const YAML::Node& map, const std::string& path,
                                    const std::vector<ParamSpec>& specs,
                                    const std::vector<std::string>& extra, Index n_particles);

  // ---- BuilderHost: what the builders of scene_builders.cpp may use ----
  std::optional<Params> read_params(const YAML::Node& map, const std::string& path,
                                    const std::vector<ParamSpec>& specs,
                                    const std::vector<std::string>& extra) override {
    return read_params(map, path, specs, extra, -1);
  }
  Index particle_count() const override { return static_cast<Index>(x_.size()); }
  bool can_add(std::int64_t count, const YAML::Node& at, const std::string& path) override;
  void add_particle(const Vec3& x, const Vec3& v, double mass, bool fixed) override {
    x_.push_back(x);
    v_.push_back(v);
    m_.push_back(mass);
    fixed_.push_back(fixed ? 1 : 0);
  }
  void reserve(std::int64_t count) override {
    const auto n = x_.size() + static_cast<std::size_t>(count);
    x_.reserve(n);
    v_.reserve(n);
    m_.reserve(n);
    fixed_.reserve(n);
  }
  void set_fixed(Index id) override { fixed_[static_cast<std::size_t>(id)] = 1; }
  void set_properties(Index first, std::int64_t count, const ParticleProperties& p) override;
  Vec3 position(Index id) const override { return x_[static_cast<std::size_t>(id)]; }
  void add_group(const std::string& name, std::vector<Index> members, const YAML::Node& at,
                 const std::string& path) override;
  void add_force(const std::string& plugin, const YAML::Node& node, const std::string& path,
                 const Params& generated, const Params& defaults, bool create) override;
  void add_constraint(const std::string& plugin, const YAML::Node& node, const std::string& path,
                      const Params& generated, bool create) override;

  // ---- the steps of load() ----
  YAML::Node parse(const std::string& text);
  void read_solver(const YAML::Node& root, std::vector<PendingPlugin>& solvers);
  void assemble_system(Scene& scene);
  void read_constraint_force(const YAML::Node& n, Scene& scene);
  void read_neighbor(const YAML::Node& n, Scene& scene);
  // ---- special bonds (scene_special_bonds.cpp) ----
  void read_special_bonds(const YAML::Node& n, Scene& scene);
  /// Gives every pair force the special bonds of the scene's bonds, or
  /// reports one that cannot take them (located at `special_bonds:`).
  void apply_special_bonds(Scene& scene);
  void add_constraint_to(System& sys, PendingPlugin& p, const SceneContext& ctx,
                         const std::string& label);
  void create_plugins(Scene& scene, std::vector<PendingPlugin>& forces,
                      std::vector<PendingPlugin>& colliders,
                      std::vector<PendingPlugin>& constraints,
                      const std::vector<PendingPlugin>& solvers);

  // ---- sections ----
  void apply_overrides(YAML::Node& root);
  void read_simulation(const YAML::Node& n, Scene& scene);
  void read_box(const YAML::Node& n);
  bool read_periodic(const YAML::Node& n, const std::string& path, std::array<bool, 3>& out);
  void read_particles(const YAML::Node& n);
  void check_inside_box();
  void read_velocities(const YAML::Node& n);  // scene_velocities.cpp
  void apply_velocities(Matrix3X& v, const Eigen::VectorXd& m);
  // ---- particles and boxes from files (scene_files.cpp) ----
  fs::path scene_relative(const std::string& name) const;
  std::optional<fs::path> side_file(const YAML::Node& map, const std::string& path,
                                    const char* expected,
                                    const std::vector<std::string>& keys = {"file"});
  void read_particle_file(const YAML::Node& item, const std::string& path);
  /// A file's format (`format`, or its extension) and its contents (frame
  /// `frame`); `for_box`: the keys of simulation.box's, else a particle entry's.
  void warn_unread(const std::string& file,
                   const std::vector<import_files::Imported::Unread>& unread);
  std::optional<import_files::Imported> import_file(const YAML::Node& map, const std::string& path,
                                                    bool for_box);
  std::optional<import_files::Format> file_format(const YAML::Node& map, const std::string& path);
  std::optional<std::string> read_atom_style(const YAML::Node& n, const std::string& path);
  std::optional<long long> read_frame(const YAML::Node& n, const std::string& path);
  bool apply_masses(const YAML::Node& item, const std::string& path, import_files::Imported& in);
  bool masses_by_kind(const YAML::Node& per, const std::string& at, import_files::Imported& in);
  bool apply_types(const YAML::Node& item, const std::string& path, import_files::Imported& in);
  bool wrap_imported(const YAML::Node& item, const std::string& path, import_files::Imported& in);
  void read_box_file(const YAML::Node& n, const std::string& path);
  const PluginRecord* find_plugin(const YAML::Node& item, const std::string& path, PluginKind kind);
  void read_plugin_list(const YAML::Node& n, const char* section, PluginKind kind,
                        std::vector<PendingPlugin>& out);
  /// A constraint item's `compliance` (the host's key, not a plugin
  /// parameter): >= 0, 0 when absent.
  std::optional<PendingPlugin> builder_plugin(PluginKind kind, const std::string& plugin,
                                              const YAML::Node& node, const std::string& path,
                                              const Params& generated);
  void replace_solver(Scene& scene, PendingPlugin& p, const SceneContext& ctx,
                      const std::string& label);
  std::optional<double> read_compliance(const YAML::Node& item, const std::string& path);
  std::optional<Params> read_plugin_params(const YAML::Node& item, const std::string& path,
                                           const PluginRecord& rec,
                                           const std::vector<std::string>& generated);
  void read_output(const YAML::Node& n, const YAML::Node& top_checkpoint, Scene& scene);
  void read_output_map(const YAML::Node& n, Scene& scene);
  void read_writer_list(const YAML::Node& n, Scene& scene);
  void read_checkpoint(const YAML::Node& c, const std::string& path, Scene& scene);
  void implied_writer(const YAML::Node& at, const std::string& key_path, const std::string& plugin,
                      const std::string& file, std::int64_t every, const Params& params,
                      Scene& scene);
  bool output_file_name(const YAML::Node& at, const std::string& key_path, const std::string& v);
  void check_written_files(const Scene& scene);
  template <class Create>
  auto create(const PendingPlugin& p, Create&& create_fn) -> decltype(create_fn());

  std::string file_;
  bool marks_ = true;  // locations carry LINE:COLUMN (false: `file_` names a call, not a file)
  const PluginRegistry& registry_;
  std::vector<Override> overrides_;
  std::vector<Diagnostic> diags_;
  std::vector<std::string> warnings_;  // Scene::warnings
  YAML::Node root_;                    // the whole scene: where a missing section is reported

  // particles as read
  std::vector<Vec3> x_, v_;
  std::vector<double> m_;
  std::vector<std::uint8_t> fixed_;
  // Radii and types: empty until some particle gives one, then one per
  // particle declared so far (0 for the others), filled up to N at assembly.
  std::vector<double> radius_;
  std::vector<std::int32_t> type_;
  // Image counts (per axis, the box lengths a particle has crossed): empty
  // until a file gives some, then one per particle declared so far.
  std::vector<std::array<std::int32_t, 3>> images_;
  std::vector<ParticleEntry> entries_;
  std::optional<Domain> box_;  // simulation.box, when given and valid
  std::map<std::string, std::vector<Index>> groups_;
  std::vector<PendingPlugin> builder_forces_;       // springs made by builders
  std::vector<PendingPlugin> builder_constraints_;  // rods made by builders
  bool particles_ok_ = true;
  // Each particle file's topology (LAMMPS data files), by the file's
  // normal path, with the scene index of its first particle.
  struct DataTopology {
    Index first = 0;
    int entries = 0;    // particle entries reading the file (terms need it once)
    std::string shown;  // the file as messages name it
    std::vector<import_files::Imported::Terms> sections;
    std::vector<import_files::Imported::Unread> unread;
    std::vector<std::string> used;  // sections some term list took
  };
  std::map<std::string, DataTopology> topology_;
  // The types of the term list read_data_terms just read (LAMMPS's 1..T),
  // for read_params to give the plugin as `types` (0..T-1).
  struct DataTypes {
    std::string key, section, file;
    std::vector<long long> type;
  };
  std::optional<DataTypes> data_types_;
  std::vector<NamedPath> read_files_;  // side files: no output may overwrite them
  // What a file read for simulation.box gave, kept for a particle entry of
  // the same file, frame and format: read once, its problems said once.
  std::map<std::string, import_files::ReadResult> box_files_;
  // Where each writer's path and the checkpoint path were given (node, key).
  std::vector<std::pair<YAML::Node, std::string>> writer_nodes_;
  std::size_t beside_ = 0;  // the writer whose path gives the default checkpoint's
  YAML::Node checkpoint_node_;
  std::string checkpoint_key_;
  std::optional<VelocitySpec> velocities_;  // `velocities:`, when given and valid
  YAML::Node neighbor_node_;                // simulation.neighbor
  YAML::Node special_node_;                 // `special_bonds:`, where its problems are reported
  YAML::Node velocities_node_;
};

}  // namespace pdyn::loading
