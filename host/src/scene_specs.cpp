// The built-in sections of a scene (simulation, particles, grid, output,
// checkpoint) and the builders' keys, as ParamSpec tables: the loader reads
// them with the same reader as plugin parameters, and `pdyn schema` lists them.
#include "pdyn/host/scene_specs.hpp"

#include "pdyn/thermo.hpp"
#include "scene_builders.hpp"

namespace pdyn {

// ---------------------------------------------------------------------------
// Specifications of the built-in sections (scene_specs.hpp: `pdyn schema`
// reads them too).

std::vector<ParamSpec> simulation_specs() {
  return {
      param::required_real("dt", "s", "time step").greater_than(0),
      param::optional("steps", ParamType::Integer, "", "number of steps (or give duration)")
          .at_least(0),
      param::optional("duration", ParamType::Real, "s", "simulated time (or give steps)")
          .at_least(0),
      param::optional("threads", ParamType::Integer, "",
                      "threads for forces and solvers (default: all cores; pdyn run --threads "
                      "overrides it); results do not depend on it")
          .at_least(1)
          .at_most(1024),
  };
}

std::vector<ParamSpec> constraint_force_specs() {
  return {
      param::real("ks", 0.0, "1/s^2", "feedback on the constraint values C (pulls drift back)")
          .at_least(0),
      param::real("kd", 0.0, "1/s", "feedback on their rates Cdot (damps drift)").at_least(0),
      param::real("tolerance", 1e-12, "",
                  "conjugate gradients' relative residual for the multipliers")
          .greater_than(0)
          .at_most(1e-2),
      param::integer("max_iterations", 0, "conjugate gradients' limit (0: 10 x rows + 100)")
          .at_least(0),
  };
}

std::vector<ParamSpec> neighbor_specs() {
  return {
      param::integer("every", 1, "steps between rebuild decisions (LAMMPS's neigh_modify every)")
          .at_least(1),
      param::integer("delay", 0, "steps after a rebuild before the first decision").at_least(0),
      param::boolean("check", true,
                     "at a decision, rebuild only if a particle moved more than skin / 2 (false: "
                     "always; pairs that come within the cutoff between rebuilds are then missed)"),
  };
}

std::vector<ParamSpec> particle_specs() {
  std::vector<ParamSpec> specs = {
      param::required_vec3("position", "m", "initial position"),
      param::vec3("velocity", Vec3::Zero(), "m/s", "initial velocity"),
      param::required_real("mass", "kg", "mass").greater_than(0),
      param::boolean("fixed", false, "nailed in place"),
  };
  for (auto& s : particle_property_specs("")) specs.push_back(std::move(s));
  return specs;
}

std::vector<ParamSpec> box_specs() {
  return {
      param::required_vec3("min", "m", "corner with the smallest coordinates"),
      param::required_vec3("max", "m", "corner with the largest coordinates (> min)"),
  };
}

std::vector<ParamSpec> grid_specs() {
  ParamSpec nx = param::required("nx", ParamType::Integer, "", "particles along u");
  ParamSpec ny = param::required("ny", ParamType::Integer, "", "particles along v");
  nx.at_least(1);
  ny.at_least(1);
  std::vector<ParamSpec> specs = {
      param::required_vec3("origin", "m", "position of particle (0, 0)"),
      param::required_vec3("u", "m", "spacing vector along the first grid direction").not_zero(),
      param::required_vec3("v", "m", "spacing vector along the second grid direction").not_zero(),
      nx,
      ny,
      param::required_real("mass", "kg", "mass of each particle").greater_than(0),
      param::vec3("velocity", Vec3::Zero(), "m/s", "initial velocity of every particle"),
      param::optional("name", ParamType::String, "", "group name"),
      param::optional("pin", ParamType::IndexPairs, "",
                      "grid coordinates [i, j] of nailed particles; negative counts from the end"),
  };
  for (auto& s : particle_property_specs()) specs.push_back(std::move(s));
  return specs;
}

std::vector<ParamSpec> output_specs() {
  ParamSpec every = param::integer("every", 1, "a frame every N steps; 0: first and final only");
  every.at_least(0);
  return {
      param::optional("path", ParamType::String, "", "frames CSV: t,id,x,y,z,vx,vy,vz"),
      every,
      param::optional("energy", ParamType::String, "", "energy CSV: t,kinetic,potential,total"),
      param::boolean("unwrapped", false,
                     "append the unwrapped positions xu,yu,zu (x + images * box length) to the "
                     "frames"),
  };
}

std::vector<ParamSpec> writer_entry_keys() {
  ParamSpec every = param::integer("every", 1, "a frame every N steps");
  every.at_least(1);
  return {
      param::required("path", ParamType::String, "",
                      "the output file (for vtk the .pvd collection; its frames go beside it)"),
      every,
      param::optional("fields", ParamType::StringList, "",
                      "what to write besides positions (velocity, mass, fixed, radius, type, "
                      "force, image, id: those the writer supports); default: the writer's own "
                      "choice"),
  };
}

std::vector<ParamSpec> velocities_specs() {
  std::vector<ParamSpec> specs = temperature_params("the temperature to draw at", false);
  specs.insert(
      specs.end(),
      {
          param::integer("seed", 1, "random seed, 0 to 4294967295")
              .at_least(0)
              .at_most(4294967295.0),
          param::boolean("zero_momentum", true, "remove the total momentum"),
          param::boolean("scale", true,
                         "scale to exactly the temperature (3 n - 3 degrees of freedom, 3 n "
                         "without zero_momentum)"),
          param::optional("group", ParamType::String, "",
                          "only this group (a builder's name:); default: every free particle"),
      });
  return specs;
}

std::vector<ParamSpec> checkpoint_specs() {
  ParamSpec every = param::integer("every", 0, "a checkpoint every N steps; 0: at the end only");
  every.at_least(0);
  return {param::required("path", ParamType::String, "", "checkpoint file"), every};
}

std::vector<BuilderSpec> builder_specs() {
  std::vector<BuilderSpec> all = {
      {"grid",
       "a rectangular sheet of nx x ny particles, optionally joined by springs",
       grid_specs(),
       {{"springs",
         "Provot's spring families of the `spring` plugin",
         "spring",
         "pairs",
         {"structural", "shear", "bend"},
         {}},
        {"rods",
         "rods (distance constraints) in Provot's families, and `bending` constraints on every "
         "interior edge: constraint plugin parameters and `compliance`",
         "distance",
         "pairs",
         {"structural", "shear", "bend"},
         {},
         PluginKind::Constraint,
         {{{"bending", "bending", "quads"}}}},
        {"bending",
         "bending stiffness on every interior edge of the triangulated sheet: `dihedral` plugin "
         "parameters",
         "dihedral",
         "quads",
         {},
         {}}}}};
  for (auto& b : more_builder_specs()) all.push_back(std::move(b));
  return all;
}

}  // namespace pdyn
