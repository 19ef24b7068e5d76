// The ParamSpec tables of the scene format's built-in sections, as the scene
// loader reads them. `pdyn schema` builds the JSON Schema of a scene from
// these same tables (and from the plugins' descriptors), so that the schema
// cannot drift from what the loader accepts.
#pragma once

#include <string>
#include <vector>

#include "pdyn/params.hpp"

namespace pdyn {

/// `simulation:` (besides `solver:`, a plugin entry).
std::vector<ParamSpec> simulation_specs();
/// One `particles:` entry that is a single particle.
std::vector<ParamSpec> particle_specs();
/// `output:` (besides `checkpoint:`).
std::vector<ParamSpec> output_specs();
/// `output.checkpoint:`.
std::vector<ParamSpec> checkpoint_specs();

/// A particle builder: a `particles:` entry `{ KEY: { ... } }`.
struct BuilderSpec {
  std::string key;                ///< "grid"
  std::string doc;                ///< one line
  std::vector<ParamSpec> params;  ///< the builder's own keys
  /// Optional `springs:` key: spring families ("structural", ...), each a
  /// mapping of the `spring` plugin's parameters except the generated `pairs`.
  std::vector<std::string> spring_families;
};

/// Every builder the loader accepts. A new builder is listed here, with the
/// same specs its reader uses, and appears in the schema.
std::vector<BuilderSpec> builder_specs();

}  // namespace pdyn
