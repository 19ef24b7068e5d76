// A scene's `velocities:` section: Maxwell-Boltzmann initial velocities at
// a temperature with a seed (pdyn/host/velocities.hpp), read after the
// particles and groups, drawn when the System is assembled.
#include <fmt/format.h>

#include "loader.hpp"
#include "pdyn/error.hpp"
#include "pdyn/host/scene_specs.hpp"
#include "pdyn/host/velocities.hpp"
#include "pdyn/thermo.hpp"

namespace pdyn::loading {

void Loader::read_velocities(const YAML::Node& n) {
  if (!n.IsDefined() || n.IsNull()) return;
  const std::string path = "velocities";
  if (!check_map(n, path, "velocities: { temperature: T, seed: N }")) return;
  auto p = read_params(n, path, velocities_specs(), {}, -1);
  if (!p) return;
  VelocitySpec spec;
  try {
    spec.kT = temperature_kT(*p);
  } catch (const ParamError& e) {
    const YAML::Node at = n[e.param()].IsDefined() ? n[e.param()] : n;
    error(at, path + "." + e.param(), fmt::format("{}.{}: {}", path, e.param(), e.what()));
    return;
  }
  spec.seed = static_cast<std::uint64_t>(p->integer("seed"));
  spec.zero_momentum = p->boolean("zero_momentum");
  spec.scale = p->boolean("scale");
  if (p->has("group")) {
    const std::string& name = p->string("group");
    const auto g = groups_.find(name);
    if (g == groups_.end()) {
      std::vector<std::string> names;
      for (const auto& kv : groups_) names.push_back(kv.first);
      error(
          n["group"], path + ".group",
          fmt::format("{}.group: no group is named '{}' (expected one of: {})", path, name,
                      names.empty() ? "none defined" : fmt::format("{}", fmt::join(names, ", "))));
      return;
    }
    spec.members = g->second;
  }
  velocities_ = std::move(spec);
  velocities_node_ = n;
}

// Before the System exists: the velocities are part of the particles its
// forces' factories see.
void Loader::apply_velocities(Matrix3X& v, const Eigen::VectorXd& m) {
  if (!velocities_) return;
  try {
    maxwell_boltzmann(v, m, fixed_, *velocities_);
  } catch (const Error& e) {
    error(velocities_node_, "velocities", fmt::format("velocities: {}", e.what()));
  }
}

}  // namespace pdyn::loading
