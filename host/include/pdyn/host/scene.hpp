// Scenes: a YAML file assembled into a ready-to-run system.
#pragma once

#include <array>
#include <filesystem>
#include <map>
#include <memory>
#include <numeric>
#include <optional>
#include <string>
#include <vector>

#include "pdyn/host/export.hpp"
#include "pdyn/host/registry.hpp"
#include "pdyn/kernel/neighbor_schedule.hpp"
#include "pdyn/system.hpp"

namespace pdyn {

/// One located problem: `location` is "FILE:LINE:COLUMN", "FILE" or
/// "--set PATH=VALUE"; `message` is "what is wrong (what was expected)".
struct PDYN_HOST_API Diagnostic {
  std::string location;
  std::string message;
  std::string text() const { return location + ": " + message; }
};

/// The scene is invalid: exit status 2. what() holds every diagnostic, one
/// per line.
class PDYN_HOST_API SceneError : public Error {
 public:
  explicit SceneError(std::vector<Diagnostic> diagnostics);
  const std::vector<Diagnostic>& diagnostics() const noexcept { return diagnostics_; }

 private:
  std::vector<Diagnostic> diagnostics_;
};

/// A `--set key.path=value` override: path like `forces[0].g`, value YAML.
struct PDYN_HOST_API Override {
  std::string path;
  std::string value;
};
/// Parses "key.path=value"; throws SceneError if there is no '='.
PDYN_HOST_API Override parse_override(const std::string& text);

/// One writer of `output:` (a writer plugin, pdyn/writer.hpp), checked: the
/// runner creates it when the run starts.
struct PDYN_HOST_API WriterSpec {
  PluginRecord record;              ///< the writer plugin (keeps its library loaded)
  std::string label;                ///< "vtk (scene.yaml:9:5)", as in messages
  std::filesystem::path path;       ///< the scene's `path:`
  std::int64_t every = 1;           ///< a frame every `every` steps; 0: first and final only
  std::vector<std::string> fields;  ///< the fields asked for (or the writer's defaults)
  Params params;                    ///< the plugin's own checked parameters
};

struct OutputSpec {
  /// In scene order. The mapping form `output: { path, every, energy,
  /// unwrapped }` gives a `csv` writer (path, unwrapped) and an `energy`
  /// writer, both every `every` steps.
  std::vector<WriterSpec> writers;
  std::filesystem::path checkpoint;   ///< checkpoint file; empty: none unless interrupted
  std::int64_t checkpoint_every = 0;  ///< a checkpoint every N steps (and at the end); 0: end only
  /// The frame schedule when there is no writer: 1 (a scene without
  /// output), or the mapping form's `every`. Adaptive solvers without dense
  /// output stop on its frame times, so it still shapes their steps.
  std::int64_t every = 1;
  /// The frame schedule the run steps through, in steps: the greatest
  /// common divisor of the writers' `every` (0: first and final frames
  /// only), or `every` when there is no writer.
  std::int64_t period() const {
    if (writers.empty()) return every;
    std::int64_t g = 0;
    for (const auto& w : writers) g = std::gcd(g, w.every);
    return g;
  }
  /// Without `checkpoint`, an interrupted run checkpoints to this path with
  /// .ckpt: output.path in the mapping form, the first writer's path in the
  /// list form; empty: `<scene name>.ckpt`.
  std::filesystem::path checkpoint_beside;
};

/// One plugin object as the scene declared it, with its checked parameters:
/// what a renderer or viewer needs to draw it (springs from its particle
/// pairs and triples, obstacles from their shape parameters) without
/// knowing the plugin's insides. Builders' springs are listed too.
struct PDYN_HOST_API PluginUse {
  PluginKind kind = PluginKind::Force;
  std::string type;   ///< the plugin's name, the scene's `type:`
  std::string label;  ///< "spring (scene.yaml:12:5)", as in messages
  Params params;
};

/// A loaded, validated scene, ready for the runner.
struct PDYN_HOST_API Scene {
  std::string file;
  std::unique_ptr<System> system;
  std::shared_ptr<Solver> solver;
  std::string solver_name;
  std::string solver_label;  ///< "rk4 (scene.yaml:3:11)", for messages
  Params solver_params;      ///< the solver's checked parameters: to make a fresh one
  /// The scene after overrides, as canonical YAML without simulation.steps
  /// and simulation.duration: what a checkpoint must match to be resumed.
  std::string canonical_text;
  double dt = 0.0;         ///< step, s
  std::int64_t steps = 0;  ///< number of steps
  double end_time = 0.0;   ///< time after the last step, s (steps * dt, or the duration)
  int threads = 0;         ///< simulation.threads; 0: not given (pdyn::default_threads)
  OutputSpec output;
  std::map<std::string, std::vector<Index>> groups;
  /// Every force and collider object, in the order the system holds them.
  std::vector<PluginUse> uses;
  /// The library of each plugin object, by its label: named in fault messages.
  std::map<std::string, std::filesystem::path> libraries;
  /// The traits each force object's plugin declares, by its label: the
  /// runner's energy check needs to know which forces only dissipate.
  std::map<std::string, ForceTraits> force_traits;
  /// simulation.constraint_force: Witkin's feedback terms and CG settings.
  ConstraintFeedback constraint_feedback;
  /// simulation.neighbor: when the pair forces' neighbor lists are rebuilt
  /// (LAMMPS's neigh_modify every / delay / check); default Verlet's rule.
  RebuildSchedule neighbor_schedule;
  /// What the scene loaded but will not use, one line each, located
  /// ("data.lmp:40:1: the file's Bonds (12 rows) are not read ..."): every
  /// host shows them (pdyn validate and run on stderr, Python as warnings).
  std::vector<std::string> warnings;
  /// `special_bonds:`, the pair forces' weights w12, w13, w14 of particles
  /// one, two and three bonds apart (pdyn/special_bonds.hpp); none: every
  /// pair at full weight. Objects added later (add_plugin) follow it.
  std::optional<std::array<double, 3>> special_bonds;
};

/// Reads, validates and assembles the scene in `file`, with `overrides`
/// applied first. Throws SceneError (bad scene) or PluginError (a plugin
/// the scene needs cannot be used).
PDYN_HOST_API Scene load_scene(const std::filesystem::path& file, const PluginRegistry& registry,
                               const std::vector<Override>& overrides = {});
/// The same, from text; `file` only names it in messages.
PDYN_HOST_API Scene load_scene_text(const std::string& text, const std::string& file,
                                    const PluginRegistry& registry,
                                    const std::vector<Override>& overrides = {});

/// Adds one plugin object to the assembled `scene`, or replaces its solver:
/// `text` is what a scene would hold for it, as YAML (`{type: spring, ks:
/// 100, pairs: [[0, 1]]}`, one item of `forces:` or `colliders:`, or the
/// `solver:` mapping), checked exactly as a scene's is (names, types, ranges,
/// particle indices against the current particles). `origin` names the
/// caller in messages and, with the plugin's name, labels the object
/// ("spring (ORIGIN)"): give each call its own. Returns that label. Throws
/// SceneError (diagnostics located at `origin`) or PluginError; on a throw
/// the scene is unchanged.
PDYN_HOST_API std::string add_plugin(Scene& scene, const PluginRegistry& registry, PluginKind kind,
                                     const std::string& text, const std::string& origin);

}  // namespace pdyn
