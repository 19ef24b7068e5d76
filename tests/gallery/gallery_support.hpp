// Helpers for the gallery tests: load a scene of configs/ exactly as `pdyn
// run` would, and step it through its whole run.
#pragma once

#include <functional>

#include "support/physics_support.hpp"
#include "support/test_support.hpp"

namespace pdyn::test {

inline Scene LoadConfig(const std::string& name) {
  return load_scene(source_path("configs/" + name), shipped_plugins());
}

/// Steps `scene` through all its steps (h = dt; these scenes' durations are
/// whole numbers of steps), calling `each` after every step.
inline void RunAll(Scene& scene, const std::function<void(std::int64_t)>& each = {}) {
  for (std::int64_t k = 1; k <= scene.steps; ++k) {
    TakeStep(scene, k, scene.dt);
    if (each) each(k);
  }
}

}  // namespace pdyn::test
