// The ParamSpec tables of the scene format's built-in sections, as the scene
// loader reads them. `pdyn schema` builds the JSON Schema of a scene from
// these same tables (and from the plugins' descriptors), so that the schema
// cannot drift from what the loader accepts.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "pdyn/host/export.hpp"
#include "pdyn/params.hpp"
#include "pdyn/plugin.hpp"

namespace pdyn {

/// `simulation:` (besides `solver:`, a plugin entry).
PDYN_HOST_API std::vector<ParamSpec> simulation_specs();
/// `simulation.box:` besides `periodic` (a list of three booleans, which no
/// ParamType describes: the loader reads it itself).
PDYN_HOST_API std::vector<ParamSpec> box_specs();
/// `simulation.constraint_force:` (Witkin's constraint force, pdyn::ConstraintFeedback).
PDYN_HOST_API std::vector<ParamSpec> constraint_force_specs();
/// simulation.neighbor: the neighbor lists' rebuild schedule.
PDYN_HOST_API std::vector<ParamSpec> neighbor_specs();
/// One `particles:` entry that is a single particle.
PDYN_HOST_API std::vector<ParamSpec> particle_specs();
/// `output:` (besides `checkpoint:`).
PDYN_HOST_API std::vector<ParamSpec> output_specs();
/// The keys of one entry of the list form of `output:` besides `type` and
/// the writer plugin's own parameters: path, every, fields. A writer's
/// parameters may not take these names (the registry refuses it).
PDYN_HOST_API std::vector<ParamSpec> writer_entry_keys();
/// `velocities:` (Maxwell-Boltzmann initial velocities, pdyn/host/velocities.hpp).
PDYN_HOST_API std::vector<ParamSpec> velocities_specs();
/// `output.checkpoint:`, and the top-level `checkpoint:` of a scene whose
/// `output:` is a list.
PDYN_HOST_API std::vector<ParamSpec> checkpoint_specs();

/// A key of a builder that holds a mapping: the parameters of a force
/// plugin the builder creates (less the particle list it generates), a
/// mapping of families of those, or a fixed set of keys (a region).
struct PDYN_HOST_API BuilderNested {
  std::string key;                    ///< "springs", "bend", "box"
  std::string doc;                    ///< one line
  std::string plugin;                 ///< force plugin ("spring"); empty: `specs`
  std::string generated;              ///< the plugin's key the builder fills ("pairs")
  std::vector<std::string> families;  ///< non-empty: { family: { plugin params }, ... }
  std::vector<ParamSpec> specs;       ///< the keys, when `plugin` is empty
  /// Constraint: `plugin` is a constraint plugin, whose entries also take
  /// the host's `compliance` (a builder's rods).
  PluginKind kind = PluginKind::Force;
  /// Families whose plugin differs from `plugin`: { family, plugin, generated }.
  std::vector<std::array<std::string, 3>> other_families = {};
};

/// A particle builder: a `particles:` entry `{ KEY: { ... } }`.
struct PDYN_HOST_API BuilderSpec {
  std::string key;                    ///< "grid"
  std::string doc;                    ///< one line
  std::vector<ParamSpec> params;      ///< the builder's own keys
  std::vector<BuilderNested> nested;  ///< its keys that hold mappings
};

/// Every builder the loader accepts. A new builder is listed here, with the
/// same specs its reader uses, and appears in the schema.
PDYN_HOST_API std::vector<BuilderSpec> builder_specs();

}  // namespace pdyn
