// libFuzzer target: the scene loader, --set overrides and a few steps of
// whatever scene survives validation.
//
// The input is scene YAML; its lines of the form "#set KEY.PATH=VALUE" (YAML
// comments, so the seeds stay valid scenes) are also applied as --set
// overrides. Every outcome must be a scene that loads or a pdyn::Error; any
// other exception, crash, hang or sanitizer report is a finding.
#include <algorithm>
#include <cstdint>
#include <sstream>
#include <string>

#include "pdyn/host/registry.hpp"
#include "pdyn/host/runner.hpp"
#include "pdyn/host/scene.hpp"

namespace {

const pdyn::PluginRegistry& registry() {
  static const pdyn::PluginRegistry r = [] {
    pdyn::PluginRegistry reg;
    reg.discover(pdyn::PluginRegistry::search_path({}));
    return reg;
  }();
  return r;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    std::vector<pdyn::Override> overrides;
    std::istringstream lines(text);
    for (std::string line; std::getline(lines, line);) {
      if (line.rfind("#set ", 0) == 0) overrides.push_back(pdyn::parse_override(line.substr(5)));
    }
    pdyn::Scene scene = pdyn::load_scene_text(text, "fuzz.yaml", registry(), overrides);
    // Simulate briefly, without output files, if the scene is small enough
    // to keep each input fast.
    if (scene.system->size() <= 5000) {
      scene.output = {};
      scene.steps = std::min<std::int64_t>(scene.steps, 5);
      scene.end_time = static_cast<double>(scene.steps) * scene.dt;
      pdyn::run_scene(scene);
    }
  } catch (const pdyn::Error&) {
    // A reported problem: the expected outcome for most inputs.
  }
  return 0;
}
