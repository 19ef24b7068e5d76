// pdyn/plugin.hpp — declaring a plugin: its descriptor, factory and entry point.
//
// A plugin library holds exactly one plugin. It exports two C symbols, made
// by PDYN_PLUGIN: the ABI version (read first, so a mismatched library is
// refused before any of its C++ types are touched) and the descriptor. A
// minimal force plugin:
//
//   #include <pdyn/plugin.hpp>
//   class Wind final : public pdyn::Force { ... };
//   static pdyn::PluginDescriptor describe() {
//     pdyn::PluginDescriptor d;
//     d.kind = pdyn::PluginKind::Force;
//     d.name = "wind";
//     d.version = "1.0.0";
//     d.description = "uniform wind: f = k (w - v)";
//     d.params = {pdyn::param::vec3("w", {1, 0, 0}, "m/s", "wind velocity")};
//     d.create_force = [](const pdyn::Params& p, const pdyn::SceneContext&) {
//       return std::make_unique<Wind>(p.vec3("w"));
//     };
//     return d;
//   }
//   PDYN_PLUGIN(describe)
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "pdyn/collider.hpp"
#include "pdyn/constraint.hpp"
#include "pdyn/error.hpp"
#include "pdyn/export.hpp"
#include "pdyn/force.hpp"
#include "pdyn/params.hpp"
#include "pdyn/particles.hpp"
#include "pdyn/solver.hpp"
#include "pdyn/version.hpp"
#include "pdyn/writer.hpp"

namespace pdyn {

/// Writer since ABI 5 (pdyn/writer.hpp), Constraint since ABI 7
/// (pdyn/constraint.hpp).
enum class PluginKind { Force, Solver, Collider, Writer, Constraint };

/// "force", "solver", "collider", "writer" or "constraint".
PDYN_API const char* kind_name(PluginKind kind);

/// What a factory may look at besides its parameters: the scene's initial
/// particles (e.g. for rest lengths) and its named particle groups.
struct PDYN_API SceneContext {
  ParticleView particles;
  const std::map<std::string, std::vector<Index>>* groups = nullptr;
};

/// Properties a force declares; the conformance kit checks each claim.
struct ForceTraits {
  /// Depends only on relative positions and velocities of the particles it
  /// joins (springs): momentum and angular momentum are conserved.
  bool internal = false;
  /// Never does positive work: f . v <= 0 (drag).
  bool dissipative = false;
  /// Since ABI 4. Infinite where two particles coincide, as a 1/r^n pair
  /// potential is (Lennard-Jones): the conformance kit does not ask it for
  /// finite values on coincident particles; a run that brings two together
  /// stops with the force named, as for any non-finite force.
  bool singular = false;
};

/// Properties a solver declares; the conformance kit checks each claim.
struct SolverTraits {
  int order = 0;            ///< global order of accuracy (1 euler, 4 rk4), 0 if unknown
  bool symplectic = false;  ///< preserves phase-space volume
};

using ForceFactory = std::function<std::unique_ptr<Force>(const Params&, const SceneContext&)>;
using SolverFactory = std::function<std::unique_ptr<Solver>(const Params&, const SceneContext&)>;
using ColliderFactory =
    std::function<std::unique_ptr<Collider>(const Params&, const SceneContext&)>;
/// Creates a writer: opens (or, resuming, continues) its output. May throw
/// pdyn::Error naming the file, or pdyn::ResumeError.
using WriterFactory = std::function<std::unique_ptr<Writer>(const Params&, const WriterContext&)>;
using ConstraintFactory =
    std::function<std::unique_ptr<Constraint>(const Params&, const SceneContext&)>;

/// Everything the host knows about a plugin before creating one.
struct PluginDescriptor {
  PluginKind kind = PluginKind::Force;
  std::string name;         ///< the scene's `type:`, [a-z0-9_]+
  std::string version;      ///< the plugin's own version, e.g. "1.0.0"
  std::string description;  ///< one line, with the force law or method
  std::vector<ParamSpec> params;
  ForceTraits force_traits;
  SolverTraits solver_traits;
  ForceFactory create_force;        ///< set for kind Force
  SolverFactory create_solver;      ///< set for kind Solver
  ColliderFactory create_collider;  ///< set for kind Collider
  // Since ABI 5.
  WriterTraits writer_traits;   ///< kind Writer: fields it writes, whether it needs energy
  WriterFactory create_writer;  ///< set for kind Writer
  WriterReader read_back;       ///< kind Writer, optional: reads its output back (pdyn check)
  // Since ABI 7. The host reads these only from plugins built for ABI 7 or
  // later: a plugin built for ABI 6 has a descriptor that ends above.
  ConstraintFactory create_constraint;  ///< set for kind Constraint
};

}  // namespace pdyn

#define PDYN_PLUGIN_EXPORT __attribute__((visibility("default")))

// How the plugin's own translation unit was compiled (pdyn::kBuildOptimised),
// recorded by PDYN_PLUGIN so that `pdyn check` can warn about a plugin built
// without optimisation, which runs one to two orders of magnitude slower. An
// optional symbol: libraries built before it are loaded as before.
#ifdef __OPTIMIZE__
#define PDYN_PLUGIN_BUILD_FLAGS_ 1u
#else
#define PDYN_PLUGIN_BUILD_FLAGS_ 0u
#endif

/// The descriptor of the plugin compiled into this binary, defined by
/// PDYN_PLUGIN. A plugin's own tests, which compile the plugin's source into
/// the test program, pass it to pdyn::conformance::run_checks.
extern "C" PDYN_PLUGIN_EXPORT const ::pdyn::PluginDescriptor* pdyn_plugin_descriptor();

/// Exports the plugin described by `describe_fn` (a function returning a
/// pdyn::PluginDescriptor). Use once per plugin library, at namespace scope.
#define PDYN_PLUGIN(describe_fn)                                                           \
  extern "C" PDYN_PLUGIN_EXPORT std::uint32_t pdyn_plugin_abi_version() noexcept {         \
    return PDYN_ABI_VERSION;                                                               \
  }                                                                                        \
  extern "C" PDYN_PLUGIN_EXPORT const ::pdyn::PluginDescriptor* pdyn_plugin_descriptor() { \
    static const ::pdyn::PluginDescriptor descriptor = describe_fn();                      \
    return &descriptor;                                                                    \
  }                                                                                        \
  extern "C" PDYN_PLUGIN_EXPORT std::uint32_t pdyn_plugin_build_flags() noexcept {         \
    return PDYN_PLUGIN_BUILD_FLAGS_;                                                       \
  }
