// `--set key.path=value` overrides: parsed from the command line and
// applied to the scene's YAML before it is read, each reported at the
// override when it is wrong.
#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <optional>
#include <string>
#include <vector>

#include "loader.hpp"
#include "pdyn/text.hpp"

namespace pdyn {

Override parse_override(const std::string& text) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0) {
    throw SceneError({{"--set " + text,
                       "an override needs a key path and a value "
                       "(expected KEY.PATH=VALUE, e.g. simulation.dt=0.001)"}});
  }
  return {text.substr(0, eq), text.substr(eq + 1)};
}

namespace loading {

// ---------------------------------------------------------------------------
// --set overrides

namespace {

// One step of a key path: a mapping key, or a list index (key empty).
struct KeyStep {
  std::string key;
  long index = -1;
};

// "forces[0].g" as keys and indices; nothing if malformed.
std::optional<std::vector<KeyStep>> split_key_path(const std::string& s) {
  std::vector<KeyStep> steps;
  bool ok = true;
  std::size_t i = 0;
  while (i < s.size() && ok) {
    if (s[i] == '.') {
      ++i;
      continue;
    }
    if (s[i] == '[') {
      const auto close = s.find(']', i);
      long idx = -1;
      try {
        std::size_t used = 0;
        idx = std::stol(s.substr(i + 1, close - i - 1), &used);
        ok = close != std::string::npos && used == close - i - 1 && idx >= 0;
      } catch (const std::exception&) {
        ok = false;
      }
      steps.push_back({"", idx});
      i = close == std::string::npos ? s.size() : close + 1;
      continue;
    }
    const auto end = s.find_first_of(".[", i);
    steps.push_back({s.substr(i, end - i), -1});
    i = end == std::string::npos ? s.size() : end;
  }
  if (!ok || steps.empty()) return std::nullopt;
  return steps;
}

// Sets `value` at `steps` under `root`: "" on success, else what is wrong.
// List elements must exist; a missing mapping on the way is created, so
// --set output.path=... works for a scene without an output section.
std::string set_at_path(YAML::Node& root, const std::vector<KeyStep>& steps,
                        const YAML::Node& value) {
  YAML::Node cur;
  cur.reset(root);
  std::string walked;
  for (std::size_t k = 0; k < steps.size(); ++k) {
    const KeyStep& st = steps[k];
    const bool last = k + 1 == steps.size();
    if (st.index >= 0) {
      const std::string here = walked.empty() ? "the scene" : walked;
      if (!cur.IsSequence()) {
        return fmt::format(
            "{} is {}, so it has no element [{}] (expected a key path into "
            "the scene's existing lists)",
            here, cur.IsDefined() && !cur.IsNull() ? "not a list" : "not in the scene", st.index);
      }
      if (static_cast<std::size_t>(st.index) >= cur.size()) {
        return fmt::format("{} has no element [{}] (expected an index below {})", here, st.index,
                           cur.size());
      }
      walked += fmt::format("[{}]", st.index);
      if (last) {
        cur[st.index] = value;
      } else {
        YAML::Node next = cur[st.index];
        cur.reset(next);
      }
      continue;
    }
    if (!(cur.IsMap() || cur.IsNull())) {
      return fmt::format(
          "{} is not a mapping, so it has no key '{}' (expected a key path "
          "that follows the scene's mappings)",
          walked, st.key);
    }
    walked += (walked.empty() ? "" : ".") + st.key;
    if (last) {
      cur[st.key] = value;
    } else {
      YAML::Node next = cur[st.key];
      if (!next.IsDefined() && steps[k + 1].index < 0) next = YAML::Node(YAML::NodeType::Map);
      cur.reset(next);
    }
  }
  return "";
}

}  // namespace

void Loader::apply_overrides(YAML::Node& root) {
  for (const auto& ov : overrides_) {
    const std::string loc = fmt::format("--set {}={}", ov.path, ov.value);
    const auto steps = split_key_path(ov.path);
    if (!steps) {
      diags_.push_back(
          {loc, fmt::format("malformed key path '{}' (expected keys and [index]es, e.g. "
                            "forces[0].g)",
                            ov.path)});
      continue;
    }
    YAML::Node value;
    try {
      value = YAML::Load(ov.value);
    } catch (const YAML::Exception& e) {
      diags_.push_back({loc, fmt::format("the value is not valid YAML: {} (expected a YAML "
                                         "value, e.g. 0.5 or [0, 0, -9.81])",
                                         e.msg)});
      continue;
    }
    if (std::string problem = set_at_path(root, *steps, value); !problem.empty()) {
      diags_.push_back({loc, std::move(problem)});
    }
  }
}

}  // namespace loading
}  // namespace pdyn
