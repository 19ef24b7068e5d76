// Particle builders of the scene loader (chain, lattice, cloud, ring,
// polygon): each turns one `particles:` entry into a block of particles and
// the force objects that hold them together.
//
// The builders see the loader only through BuilderHost, so that they check
// their keys with the same ParamSpec reader as everything else, report in
// the same FILE:LINE:COLUMN format, and create their springs through the
// registry's plugins (`spring`, `angle`, `area`) by name, as the grid does.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "pdyn/host/scene_specs.hpp"
#include "pdyn/params.hpp"
#include "pdyn/types.hpp"

namespace pdyn {

// The most particles a scene may hold: about 3.5 GB of kernel state, far
// beyond any interactive scene, and a clear refusal instead of an
// out-of-memory failure for a mistyped grid size.
inline constexpr std::int64_t kMaxParticles = std::int64_t{1} << 24;

/// What a scene may say about each particle besides its motion: a radius
/// (m, >= 0) and a type (>= 0), each given or not. A scene where some
/// particles give one and others do not gives the others 0 (docs/scenes.md).
struct ParticleProperties {
  std::optional<double> radius;
  std::optional<std::int32_t> type;
};

/// The keys with which every builder gives all its particles one radius and
/// one type: `particle_radius` and `particle_type` (`radius` is a ring's own);
/// with `prefix` "", a single particle's `radius` and `type`.
std::vector<ParamSpec> particle_property_specs(const std::string& prefix = "particle_");
/// The properties those keys (or a single particle's `radius` and `type`,
/// with `prefix` "") give in `p`.
ParticleProperties particle_properties(const Params& p, const std::string& prefix = "particle_");

class BuilderHost {
 public:
  virtual ~BuilderHost() = default;

  /// Reports a problem at `at` (or, for a --set value, at the override).
  virtual void error(const YAML::Node& at, const std::string& path, std::string message) = 0;
  /// Reports and returns false unless `n` is a mapping.
  virtual bool check_map(const YAML::Node& n, const std::string& path, const char* what) = 0;
  /// Reads the keys of `map` described by `specs`; `extra` keys are allowed
  /// and left to the caller. Nothing: a problem was reported.
  virtual std::optional<Params> read_params(const YAML::Node& map, const std::string& path,
                                            const std::vector<ParamSpec>& specs,
                                            const std::vector<std::string>& extra) = 0;
  /// Particles declared so far: the first id of the next builder.
  virtual Index particle_count() const = 0;
  /// Reports and returns false if `count` more particles would exceed the
  /// scene's limit.
  virtual bool can_add(std::int64_t count, const YAML::Node& at, const std::string& path) = 0;
  virtual void add_particle(const Vec3& x, const Vec3& v, double mass, bool fixed) = 0;
  /// Room for `count` more particles: a builder of a million particles
  /// reserves once instead of growing the lists by doubling.
  virtual void reserve(std::int64_t count) = 0;
  virtual void set_fixed(Index id) = 0;
  /// Gives particles first .. first + count - 1 the properties `p` holds
  /// (nothing for a property it does not hold).
  virtual void set_properties(Index first, std::int64_t count, const ParticleProperties& p) = 0;
  /// Position of a particle declared so far, m.
  virtual Vec3 position(Index id) const = 0;
  /// Makes `members` the group `name` (the builder's `name:` key, at `at`);
  /// reports a duplicate.
  virtual void add_group(const std::string& name, std::vector<Index> members, const YAML::Node& at,
                         const std::string& path) = 0;
  /// Queues one force object of plugin `plugin` whose parameters are the
  /// keys of `node` (a mapping, or undefined for none) plus `generated` (the
  /// particle lists the builder made). Keys of `defaults` that `node` does
  /// not give replace the plugin's own defaults. With `create` false the
  /// keys are only checked (a family that yields no pairs).
  virtual void add_force(const std::string& plugin, const YAML::Node& node, const std::string& path,
                         const Params& generated, const Params& defaults, bool create) = 0;
  /// The same for a constraint plugin (a builder's rods): the keys of
  /// `node` are the plugin's parameters and the host's `compliance`.
  virtual void add_constraint(const std::string& plugin, const YAML::Node& node,
                              const std::string& path, const Params& generated, bool create) = 0;
};

/// The builder keys that read_builder() accepts as a particles entry.
const std::vector<std::string>& builder_names();

/// The specs of those builders, the same tables their readers check
/// against, for `pdyn schema` (through builder_specs()).
std::vector<BuilderSpec> more_builder_specs();

/// The grid builder's keys (scene_specs.cpp), as builder_specs() lists them.
std::vector<ParamSpec> grid_specs();

/// Reads the `grid:` entry `g` at `path` (e.g. "particles[0].grid"): a
/// rectangular sheet of particles with Provot's cloth springs.
void read_grid(BuilderHost& host, const YAML::Node& g, const std::string& path);

/// Reads the builder `name` (one of builder_names()) from `node`, a
/// particles entry's value, at `path` (e.g. "particles[2].chain").
void read_builder(BuilderHost& host, const std::string& name, const YAML::Node& node,
                  const std::string& path);

}  // namespace pdyn
