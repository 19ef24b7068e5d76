// The scene's `special_bonds:` (issue 44 item 3): the pair forces' weights
// of particles one, two and three bonds apart, as LAMMPS's `special_bonds
// lj w12 w13 w14` (pdyn/special_bonds.hpp). The bonds are every `pairs:`
// list of the scene's forces and constraints (springs, FENE bonds, rods,
// builders' springs), as LAMMPS counts every bond of its topology; every
// pair force receives the same set. Members of Loader (loader.hpp).
#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <variant>

#include "loader.hpp"
#include "pdyn/pair.hpp"
#include "pdyn/special_bonds.hpp"

namespace pdyn::loading {

namespace {

// LAMMPS's named settings (its special_bonds doc page), Lennard-Jones part.
struct Preset {
  const char* name;
  std::array<double, 3> lj;
};
constexpr Preset kPresets[] = {{"fene", {0.0, 1.0, 1.0}},
                               {"amber", {0.0, 0.0, 0.5}},
                               {"charmm", {0.0, 0.0, 0.0}},
                               {"dreiding", {0.0, 0.0, 1.0}}};

constexpr const char* kExpected =
    "expected fene, amber, charmm, dreiding, or { lj: [w12, w13, w14] } with each weight from 0 "
    "to 1";

// Every `pairs:` list of the scene's forces and constraints.
std::vector<IndexPair> scene_bonds(const Scene& scene) {
  std::vector<IndexPair> bonds;
  for (const PluginUse& u : scene.uses) {
    if (u.kind != PluginKind::Force && u.kind != PluginKind::Constraint) continue;
    const auto it = u.params.values().find("pairs");
    if (it == u.params.values().end()) continue;
    if (const auto* pairs = std::get_if<std::vector<IndexPair>>(&it->second)) {
      bonds.insert(bonds.end(), pairs->begin(), pairs->end());
    }
  }
  return bonds;
}

}  // namespace

void Loader::read_special_bonds(const YAML::Node& n, Scene& scene) {
  if (!n.IsDefined() || n.IsNull()) return;
  special_node_ = n;
  if (n.IsScalar()) {
    for (const Preset& p : kPresets) {
      if (n.Scalar() == p.name) {
        scene.special_bonds = p.lj;
        return;
      }
    }
    error(n, "special_bonds",
          fmt::format("special_bonds: '{}' is not a setting ({})", shown(n), kExpected));
    return;
  }
  if (!check_map(n, "special_bonds", kExpected)) return;
  check_keys(n, "special_bonds", {"lj"});
  const YAML::Node lj = n["lj"];
  std::array<double, 3> w{};
  bool ok = lj.IsDefined() && lj.IsSequence() && lj.size() == 3;
  for (std::size_t k = 0; ok && k < 3; ++k) {
    ok = lj[k].IsScalar() && YAML::convert<double>::decode(lj[k], w[k]) && w[k] >= 0.0 &&
         w[k] <= 1.0;
  }
  if (!ok) {
    error(lj.IsDefined() ? lj : n, "special_bonds.lj",
          fmt::format("special_bonds.lj: {} (expected three weights [w12, w13, w14] of the "
                      "pairs one, two and three bonds apart, each from 0 to 1)",
                      lj.IsDefined() ? "'" + shown(lj) + "' is not three weights" : "is missing"));
    return;
  }
  scene.special_bonds = w;
}

// A pair force that would ignore special bonds: built against an SDK before
// them. Empty when `force` takes them or is no pair force.
std::string special_bonds_refusal(const Force& force, const std::string& label,
                                  const fs::path& library) {
  if (dynamic_cast<const SpecialBondsTarget*>(&force) != nullptr) return {};
  if (dynamic_cast<const PairReference*>(&force) == nullptr) return {};
  return fmt::format(
      "the pair force {} from {} does not take special bonds (expected a pair "
      "force built against pdyn 0.10 or later, whose PairForce applies them: "
      "rebuild the plugin, or remove special_bonds)",
      label, library.string());
}

void Loader::apply_special_bonds(Scene& scene) {
  if (!scene.special_bonds) return;
  System& sys = *scene.system;
  const std::vector<IndexPair> bonds = scene_bonds(scene);
  auto special =
      std::make_shared<const SpecialBonds>(special_bonds(sys.size(), bonds, *scene.special_bonds));
  int targets = 0;
  for (const auto& entry : sys.force_objects()) {
    if (auto* t = dynamic_cast<SpecialBondsTarget*>(entry.force.get())) {
      t->set_special_bonds(special);
      ++targets;
      continue;
    }
    const auto lib = scene.libraries.find(entry.label);
    const std::string why = special_bonds_refusal(
        *entry.force, entry.label, lib == scene.libraries.end() ? fs::path() : lib->second);
    if (!why.empty()) error(special_node_, "special_bonds", "special_bonds: " + why);
  }
  if (!marks_) return;  // an object added later: the scene was warned when it loaded
  if (bonds.empty()) {
    warnings_.push_back(fmt::format(
        "{}: special_bonds: the scene has no bonds, so no pair is weighted (bonds are the "
        "`pairs:` of its forces and constraints)",
        where(special_node_, "special_bonds")));
  } else if (targets == 0) {
    warnings_.push_back(
        fmt::format("{}: special_bonds: the scene has no pair force to weigh its pairs",
                    where(special_node_, "special_bonds")));
  }
}

}  // namespace pdyn::loading
