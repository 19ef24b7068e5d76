// Selections of particles for per-particle forces (pdyn/selection.hpp).
#include "pdyn/selection.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "pdyn/text.hpp"

namespace pdyn {

std::vector<ParamSpec> selection_params() {
  return {
      param::optional("group", ParamType::String, "",
                      "act only on this group (a builder's name:); default: every particle"),
      param::optional("ids", ParamType::IndexList, "",
                      "act only on these particles; default: every particle"),
  };
}

Selection Selection::from_params(const Params& params, const SceneContext& ctx) {
  const bool has_group = params.has("group"), has_ids = params.has("ids");
  if (has_group && has_ids) {
    throw ParamError("ids", "both 'group' and 'ids' are given (expected at most one of them)");
  }
  Selection s;
  if (has_group) {
    const std::string& name = params.string("group");
    if (ctx.groups) {
      if (const auto it = ctx.groups->find(name); it != ctx.groups->end()) {
        s.all_ = false;
        s.ids_ = it->second;
        return s;
      }
    }
    std::vector<std::string> names;
    if (ctx.groups) {
      for (const auto& [n, members] : *ctx.groups) names.push_back(n);
    }
    if (names.empty()) {
      throw ParamError("group", fmt::format("unknown group '{}' (expected a group named by a "
                                            "builder's 'name:'; the scene defines none)",
                                            name));
    }
    const std::string guess = closest_match(name, names);
    throw ParamError(
        "group",
        fmt::format("unknown group '{}' ({}expected one of: {})", name,
                    guess.empty() ? "" : fmt::format("did you mean '{}'? ", guess), join(names)));
  } else if (has_ids) {
    const auto& ids = params.indices("ids");
    if (ids.empty()) {
      throw ParamError("ids",
                       "is empty (expected at least one particle index; leave 'ids' out "
                       "for every particle)");
    }
    require_distinct_ids(params, "ids");
    s.all_ = false;
    s.ids_ = ids;
  }
  return s;
}

std::vector<std::uint8_t> Selection::mask(Index n) const {
  if (all_) return {};
  std::vector<std::uint8_t> flags(static_cast<std::size_t>(n), 0);
  for (const Index i : ids_) flags[static_cast<std::size_t>(i)] = 1;
  return flags;
}

}  // namespace pdyn
