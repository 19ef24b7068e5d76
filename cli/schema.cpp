// `pdyn schema`: the JSON Schema (draft 2020-12) of the scene format, built
// from the loader's own ParamSpec tables (scene_specs.hpp) and the
// descriptors of every plugin found, for editors (yaml-language-server) and
// for checking scenes outside pdyn.
//
// What it cannot say, and `pdyn validate` still checks: particle indices below
// the scene's particle count, group names, a factory's own refusals.
//   exit 0: written; 1: the output file could not be written.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <ostream>

#include "commands.hpp"
#include "pdyn/host/registry.hpp"
#include "pdyn/host/scene_specs.hpp"
#include "pdyn/host/side_files.hpp"
#include "sdk_commands.hpp"

namespace pdyn::cli {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

namespace {

struct SchemaArgs {
  std::vector<std::string> plugin_path;
  std::string output;
};

Json number(const ParamSpec& s, const char* type) {
  Json j{{"type", type}};
  if (s.min) j[s.min_exclusive ? "exclusiveMinimum" : "minimum"] = *s.min;
  if (s.max) j["maximum"] = *s.max;
  return j;
}

Json vec3(const ParamSpec& s) {
  Json j{{"type", "array"}, {"items", number(s, "number")}, {"minItems", 3}, {"maxItems", 3}};
  if (s.nonzero) j["not"] = Json{{"const", Json::array({0, 0, 0})}};
  return j;
}

// `checked`: indices are checked against the particle count (plugin
// parameters); builders' own index lists (grid pins) may count from the end.
Json tuples(std::size_t k, bool checked) {
  Json index{{"type", "integer"}};
  if (checked) index["minimum"] = 0;
  Json tuple{{"type", "array"}, {"items", index}};
  if (k > 0) {
    tuple["minItems"] = k;
    tuple["maxItems"] = k;
  }
  return tuple;
}

Json value_json(const ParamValue& v) {
  struct Visitor {
    Json operator()(double x) const { return std::isfinite(x) ? Json(x) : Json(); }
    Json operator()(std::int64_t x) const { return x; }
    Json operator()(bool x) const { return x; }
    Json operator()(const std::string& x) const { return x; }
    Json operator()(const Vec3& x) const { return Json::array({x.x(), x.y(), x.z()}); }
    Json operator()(const std::vector<double>& xs) const { return xs; }
    Json operator()(const std::vector<Vec3>& xs) const {
      Json a = Json::array();
      for (const auto& x : xs) a.push_back((*this)(x));
      return a;
    }
    Json operator()(const std::vector<Index>& xs) const { return xs; }
    Json operator()(const std::vector<IndexPair>& xs) const { return xs; }
    Json operator()(const std::vector<IndexTriple>& xs) const { return xs; }
    Json operator()(const std::vector<IndexQuad>& xs) const { return xs; }
    Json operator()(const std::vector<std::string>& xs) const { return xs; }
    Json operator()(const NamedReals& xs) const {
      Json o = Json::object();
      for (const auto& [name, x] : xs) o[name] = (*this)(x);
      return o;
    }
  };
  return std::visit(Visitor{}, v);
}

Json param_schema(const ParamSpec& s, bool indices_checked) {
  Json j;
  switch (s.type) {
    case ParamType::Real:
      j = number(s, "number");
      break;
    case ParamType::Integer:
      j = number(s, "integer");
      break;
    case ParamType::Boolean:
      // The loader takes 0 and 1 as well, as CSV side files do.
      j = Json::object();
      j["anyOf"] = Json::array({Json{{"type", "boolean"}}, Json{{"enum", Json::array({0, 1})}}});
      break;
    case ParamType::String:
      j = {{"type", "string"}};
      break;
    case ParamType::Vector:
      j = vec3(s);
      break;
    case ParamType::RealList:
      // A single number is the one-element list (`rest: 0.1`, one for all).
      j = Json::object();
      j["anyOf"] = Json::array(
          {number(s, "number"), Json{{"type", "array"}, {"items", number(s, "number")}}});
      break;
    case ParamType::VectorList:
      j = {{"type", "array"}, {"items", vec3(s)}};
      break;
    case ParamType::IndexList:
      j = tuples(0, indices_checked)["items"];
      break;
    case ParamType::IndexPairs:
      j = {{"type", "array"}, {"items", tuples(2, indices_checked)}};
      break;
    case ParamType::IndexTriples:
      j = {{"type", "array"}, {"items", tuples(3, indices_checked)}};
      break;
    case ParamType::IndexQuads:
      j = {{"type", "array"}, {"items", tuples(4, indices_checked)}};
      break;
    case ParamType::IntegerList:
      // A single whole number is the one-element list, as for RealList.
      j = Json::object();
      j["anyOf"] = Json::array(
          {number(s, "integer"), Json{{"type", "array"}, {"items", number(s, "integer")}}});
      break;
    case ParamType::StringList:
      j = {{"type", "array"}, {"items", {{"type", "string"}}}};
      break;
    case ParamType::NamedReals:
      // Names are identifiers (the loader's rule), each mapped to a number.
      j = {{"type", "object"},
           {"propertyNames", {{"pattern", "^[A-Za-z_][A-Za-z0-9_]*$"}}},
           {"additionalProperties", number(s, "number")}};
      break;
  }
  if (s.type == ParamType::IndexList) j = {{"type", "array"}, {"items", j}};
  std::string doc = s.doc;
  if (!s.unit.empty()) doc += fmt::format(" [{}]", s.unit);
  if (!doc.empty()) j["description"] = doc;
  if (s.fallback) {
    if (Json d = value_json(*s.fallback); !d.is_null()) j["default"] = d;
  }
  return j;
}

// A mapping of exactly these keys (plus `extra`, described by the caller).
Json object(const std::vector<ParamSpec>& specs, bool indices_checked,
            Json extra = Json::object()) {
  Json props = Json::object();
  Json required = Json::array();
  for (const auto& s : specs) {
    props[s.name] = param_schema(s, indices_checked);
    if (s.required) required.push_back(s.name);
  }
  for (auto& [k, v] : extra.items()) props[k] = v;
  Json j{{"type", "object"}, {"properties", props}, {"additionalProperties", false}};
  if (!required.empty()) j["required"] = required;
  return j;
}

std::string def_name(const PluginDescriptor& d) {
  return fmt::format("{}.{}", kind_name(d.kind), d.name);
}

// One entry of forces/colliders or simulation.solver: `type` picks the
// plugin, whose parameters then apply (if/then per plugin, so that a
// validator reports the parameter that is wrong rather than "no oneOf branch").
Json plugin_entry(const PluginRegistry& registry, PluginKind kind) {
  Json names = Json::array();
  Json branches = Json::array();
  for (const auto& name : registry.names(kind)) {
    names.push_back(name);
    branches.push_back(
        {{"if", {{"properties", {{"type", {{"const", name}}}}}, {"required", {"type"}}}},
         {"then", {{"$ref", "#/$defs/" + def_name(*registry.find(kind, name)->descriptor)}}}});
  }
  Json j{{"type", "object"},
         {"description", fmt::format("a {} plugin: `type` names it, the other keys are its "
                                     "parameters",
                                     kind_name(kind))},
         {"required", {"type"}},
         {"properties", {{"type", {{"enum", names}}}}}};
  if (!branches.empty()) j["allOf"] = branches;
  return j;
}

// `file` and `format` of a particle file or a box taken from one.
Json import_file_property() {
  return {{"type", "string"},
          {"minLength", 1},
          {"description",
           "a file of particles, relative to the scene's folder: pdyn's CSV (header "
           "x,y,z[,vx,vy,vz],mass[,fixed][,radius][,type]), a LAMMPS data file or text dump, "
           "or extended XYZ"}};
}

Json import_format_property() {
  return {{"enum", side_files::kParticleFileFormats},
          {"description", "the file's format, when its extension does not say"}};
}

Json import_frame_property() {
  return {
      {"type", "integer"},
      {"default", -1},
      {"description", "the frame of a LAMMPS dump or extended XYZ file: 0 the first, -1 the last"}};
}

// One definition per plugin (its parameters), and per kind the entry that
// picks one by `type`.
Json plugin_defs(const PluginRegistry& registry) {
  Json defs = Json::object();
  for (const auto& r : registry.plugins()) {
    const PluginDescriptor& d = *r.descriptor;
    Json type{{"const", d.name}};
    std::vector<ParamSpec> specs;
    if (d.kind == PluginKind::Writer) specs = writer_entry_keys();  // path, every, fields
    specs.insert(specs.end(), d.params.begin(), d.params.end());
    Json j = object(specs, true, Json{{"type", type}});
    j["description"] =
        fmt::format("{} {} {}: {}", kind_name(d.kind), d.name, d.version, d.description);
    defs[def_name(d)] = j;
  }
  defs["force"] = plugin_entry(registry, PluginKind::Force);
  defs["collider"] = plugin_entry(registry, PluginKind::Collider);
  defs["solver"] = plugin_entry(registry, PluginKind::Solver);
  defs["writer"] = plugin_entry(registry, PluginKind::Writer);
  defs["constraint"] = plugin_entry(registry, PluginKind::Constraint);

  return defs;
}

// simulation: time step, run length, solver, box (or a file's box).
Json simulation_schema() {
  // periodic is a list of three booleans, which no ParamType describes.
  Json flag = Json::object();
  flag["anyOf"] = Json::array({Json{{"type", "boolean"}}, Json{{"enum", Json::array({0, 1})}}});
  Json periodic{{"type", "array"},
                {"items", flag},
                {"minItems", 3},
                {"maxItems", 3},
                {"default", Json::array({false, false, false})},
                {"description",
                 "per axis x, y, z: periodic (a particle leaving through max re-enters at min) "
                 "or open"}};
  Json box = object(box_specs(), false, Json{{"periodic", periodic}});
  box["type"] = Json::array({"object", "null"});
  // Or the box of a file (docs/scenes.md, "Particles from LAMMPS and
  // extended XYZ files").
  box = Json{{"anyOf", Json::array({box, Json{{"type", "object"},
                                              {"properties",
                                               {{"file", import_file_property()},
                                                {"format", import_format_property()},
                                                {"frame", import_frame_property()},
                                                {"periodic", periodic}}},
                                              {"required", {"file"}},
                                              {"additionalProperties", false}}})}};
  box["description"] =
      "the simulation box: periodic along some axes, open (not a wall) along the others";
  Json constraint_force = object(constraint_force_specs(), false);
  constraint_force["type"] = Json::array({"object", "null"});
  constraint_force["description"] =
      "Witkin's constraint force: feedback terms and conjugate gradients' settings";
  Json simulation = object(simulation_specs(), false,
                           Json{{"solver", {{"$ref", "#/$defs/solver"}}},
                                {"box", box},
                                {"constraint_force", constraint_force}});
  simulation["description"] = "time step, run length and solver (default rk4)";
  simulation["oneOf"] = Json::array({{{"required", {"steps"}}}, {{"required", {"duration"}}}});
  return simulation;
}

// output (a list of writers or the mapping form) and the top-level
// checkpoint, returned as {output, checkpoint}.
std::pair<Json, Json> output_schemas() {
  Json checkpoint = object(checkpoint_specs(), false);
  Json output_map = object(output_specs(), false, Json{{"checkpoint", checkpoint}});
  output_map["type"] = Json::array({"object", "null"});
  output_map["description"] =
      "one csv writer (path), one energy writer (energy) and the checkpoints";
  Json output{
      {"description",
       "what is written: a list of writers (docs/output.md), or the mapping "
       "{ path, every, energy, unwrapped, checkpoint }"},
      {"anyOf",
       Json::array({output_map, {{"type", "array"}, {"items", {{"$ref", "#/$defs/writer"}}}}})}};
  Json top_checkpoint = checkpoint;
  top_checkpoint["description"] = "checkpoints (also output.checkpoint in the mapping form)";
  return {output, top_checkpoint};
}

// A builder's nested mapping: a force plugin's parameters less the list
// the builder generates (or families of them), or fixed keys.
// The parameters of `plugin` less `generated`, and a constraint's
// `compliance`.
Json builder_plugin_keys(const PluginRegistry& registry, PluginKind kind, const std::string& plugin,
                         const std::string& generated) {
  const PluginRecord* rec = registry.find(kind, plugin);
  if (rec == nullptr) return Json{{"type", Json::array({"object", "null"})}};
  std::vector<ParamSpec> specs;
  for (const auto& s : rec->descriptor->params) {
    if (s.name != generated) specs.push_back(s);
  }
  if (kind == PluginKind::Constraint) {
    specs.push_back(param::real("compliance", 0.0, "unit/N",
                                "the row's unit per newton (m/N for a rod); 0 = rigid")
                        .at_least(0.0));
  }
  Json j = object(specs, true);
  j["type"] = Json::array({"object", "null"});
  return j;
}

Json builder_nested(const PluginRegistry& registry, const BuilderNested& n) {
  Json j;
  if (n.plugin.empty()) {
    j = object(n.specs, false);
  } else {
    j = builder_plugin_keys(registry, n.kind, n.plugin, n.generated);
  }
  j["type"] = Json::array({"object", "null"});
  if (!n.families.empty()) {
    Json families = Json::object();
    for (const auto& f : n.families) families[f] = j;
    for (const auto& [family, plugin, generated] : n.other_families) {
      families[family] = builder_plugin_keys(registry, n.kind, plugin, generated);
    }
    j = {{"type", Json::array({"object", "null"})},
         {"properties", families},
         {"additionalProperties", false}};
  }
  j["description"] = n.doc;
  return j;
}

// A file of particles (docs/scenes.md, `file`): pdyn's CSV, a LAMMPS data
// or dump file, extended XYZ.
Json particle_file_schema() {
  return {{"type", "object"},
          {"properties",
           {{"file", import_file_property()},
            {"format", import_format_property()},
            {"frame", import_frame_property()},
            {"mass",
             {{"type", "number"},
              {"exclusiveMinimum", 0},
              {"description",
               "kg: every particle's mass (needed where the file has "
               "none)"}}},
            {"masses",
             {{"type", "object"},
              {"additionalProperties", {{"type", "number"}, {"exclusiveMinimum", 0}}},
              {"description",
               "kg per LAMMPS type ({ 1: 39.948 }) or per XYZ species ({ Ar: 39.948 "
               "})"}}},
            {"types",
             {{"type", "object"},
              {"additionalProperties", {{"type", "integer"}, {"minimum", 0}}},
              {"description",
               "an extended XYZ file's species as particle types ({ Ar: 1, Kr: 2 }); "
               "default 0, 1, ... in order of first appearance"}}}}},
          {"required", {"file"}},
          {"additionalProperties", false}};
}

// One item of particles: a particle, a builder or a file.
Json particle_items(const PluginRegistry& registry) {
  Json particle = object(particle_specs(), false);
  particle["description"] = "one particle";
  Json items = Json::array({particle});
  for (const auto& b : builder_specs()) {
    Json extra = Json::object();
    for (const auto& n : b.nested) extra[n.key] = builder_nested(registry, n);
    Json builder = object(b.params, false, extra);
    builder["description"] = b.doc;
    items.push_back({{"type", "object"},
                     {"properties", {{b.key, builder}}},
                     {"required", {b.key}},
                     {"additionalProperties", false}});
  }
  items.push_back(particle_file_schema());
  return items;
}

// `special_bonds:` (host/src/scene_special_bonds.cpp): a LAMMPS preset or
// three weights.
Json special_bonds_schema() {
  const Json weight{{"type", "number"}, {"minimum", 0}, {"maximum", 1}};
  return Json{
      {"description",
       "pair forces' weights of particles 1, 2 and 3 bonds apart (LAMMPS special_bonds lj); "
       "bonds are every `pairs:` of the forces and constraints"},
      {"oneOf",
       Json::array(
           {{{"enum", {"fene", "amber", "charmm", "dreiding"}}},
            {{"type", "object"},
             {"required", {"lj"}},
             {"additionalProperties", false},
             {"properties",
              {{"lj",
                {{"type", "array"}, {"items", weight}, {"minItems", 3}, {"maxItems", 3}}}}}}})}};
}

Json make_schema(const PluginRegistry& registry) {
  const Json defs = plugin_defs(registry);
  const Json simulation = simulation_schema();
  const auto [output, top_checkpoint] = output_schemas();
  const Json items = particle_items(registry);
  Json velocities = object(velocities_specs(), false);
  velocities["description"] =
      "Maxwell-Boltzmann initial velocities at a temperature (temperature or kT), with a seed";
  velocities["oneOf"] = Json::array({{{"required", {"temperature"}}}, {{"required", {"kT"}}}});
  auto plugin_list = [](const char* def) {
    return Json{{"type", Json::array({"array", "null"})},
                {"items", {{"$ref", std::string("#/$defs/") + def}}}};
  };
  Json schema{{"$schema", "https://json-schema.org/draft/2020-12/schema"},
              {"title", "pdyn scene"},
              {"description",
               "A pdyn scene (docs/scenes.md), generated by `pdyn schema` from the loader's "
               "tables and the plugins found"},
              {"type", "object"},
              {"required", {"simulation", "particles"}},
              {"properties",
               {{"simulation", simulation},
                {"output", output},
                {"checkpoint", top_checkpoint},
                {"particles", {{"type", "array"}, {"minItems", 1}, {"items", {{"oneOf", items}}}}},
                {"velocities", velocities},
                {"forces", plugin_list("force")},
                {"colliders", plugin_list("collider")},
                {"constraints", plugin_list("constraint")},
                {"special_bonds", special_bonds_schema()}}},
              {"additionalProperties", false},
              {"$defs", defs}};
  return schema;
}

int cmd_schema(const SchemaArgs& a, std::ostream& out, std::ostream& err) {
  PluginRegistry registry;
  registry.discover(
      PluginRegistry::search_path(std::vector<fs::path>(a.plugin_path.begin(), a.plugin_path.end()),
                                  DefaultFolders::LibraryAndProgram));
  for (const auto& f : registry.faults()) {
    err << fmt::format("pdyn: warning: {}: plugin '{}' left out of the schema: {}\n",
                       f.library.string(), f.plugin, f.message);
  }
  return write_text_output(make_schema(registry).dump(2) + "\n", a.output, out, err);
}

}  // namespace

SdkCommand add_schema_command(CLI::App& app) {
  auto a = std::make_shared<SchemaArgs>();
  CLI::App* sub = app.add_subcommand(
      "schema", "print the JSON Schema (draft 2020-12) of scenes with the plugins found");
  add_plugin_path_option(sub, a->plugin_path);
  sub->add_option("--output,-o", a->output, "write to this file instead of standard output");
  return {sub, [a](std::ostream& out, std::ostream& err) { return cmd_schema(*a, out, err); }};
}

}  // namespace pdyn::cli
